//! `.bpt` Bezier patch files (the Utah teapot's classic format): the first line is the
//! patch count; each patch is a line `3 3` (degrees in u and v; only bicubic patches are
//! accepted) followed by 16 lines `x y z`, four rows of four points along `u`. Blank lines
//! are skipped.

use crate::error::LoadError;
use raybench_core::Vec3;
use raybench_core::limits::MAX_BEZIER_PATCHES;
use std::path::Path;

/// Largest accepted `.bpt` file (about 30 bytes a point: far more than
/// [`MAX_BEZIER_PATCHES`] patches would need is refused before reading).
const MAX_BPT_BYTES: u64 = 1 << 30;

/// One patch read from a `.bpt` file.
#[derive(Clone, Debug, PartialEq)]
pub struct BptPatch {
    /// The line of its `3 3` header (1-based), for error messages.
    pub line: usize,
    /// Its control points, `points[4 j + i]` weighted by `B_i(u) B_j(v)`.
    pub points: [Vec3; 16],
}

/// Reads a `.bpt` file.
///
/// # Errors
/// [`LoadError::Io`] when it cannot be read, [`LoadError::Parse`] when it is too large, not
/// UTF-8 or malformed (with a line number: see [`parse_bpt`]).
pub fn load_bpt_file(path: &Path) -> Result<Vec<BptPatch>, LoadError> {
    let text = crate::io::read_text(path, MAX_BPT_BYTES, "Bezier patch file")?;
    parse_bpt(&text, path)
}

/// Parses the text of a `.bpt` file (`path` names it in errors).
///
/// # Errors
/// [`LoadError::Parse`] with the line number for a missing or malformed count, a count of
/// zero or above [`MAX_BEZIER_PATCHES`] (refused before anything is allocated), degrees
/// other than `3 3`, a point that is not three numbers, a non-finite coordinate, fewer
/// patches than declared or data after the declared patches.
pub fn parse_bpt(text: &str, path: &Path) -> Result<Vec<BptPatch>, LoadError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // Lines may end in CR alone (`crate::io::lone_cr_to_lf`).
    let text = String::from_utf8_lossy(&crate::io::lone_cr_to_lf(text.as_bytes())).into_owned();
    let text = text.as_str();
    let err = |line: usize, message: String| LoadError::Parse {
        path: path.to_owned(),
        message: format!("line {line}: {message}"),
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let last = text.lines().count();
    let (first, count_text) = lines
        .next()
        .ok_or_else(|| err(1, "empty file: expected the number of patches".into()))?;
    let count: usize = count_text.parse().map_err(|_| {
        err(
            first,
            format!("expected the number of patches, found '{count_text}'"),
        )
    })?;
    if count == 0 || count > MAX_BEZIER_PATCHES {
        return Err(err(
            first,
            format!("{count} patches declared; between 1 and {MAX_BEZIER_PATCHES} are accepted"),
        ));
    }
    // A declared count is a claim, not a size: grow as the patches arrive.
    let mut patches = Vec::with_capacity(count.min(1024));
    for k in 1..=count {
        let (line, header) = lines.next().ok_or_else(|| {
            err(
                last,
                format!(
                    "the file ends after {} patches; the first line declares {count}",
                    k - 1
                ),
            )
        })?;
        let degrees: Vec<&str> = header.split_whitespace().collect();
        if degrees != ["3", "3"] {
            return Err(err(
                line,
                format!(
                    "patch {k}: expected the degrees '3 3' (only bicubic patches are \
                     supported), found '{header}'"
                ),
            ));
        }
        let mut points = [Vec3::ZERO; 16];
        for (m, p) in points.iter_mut().enumerate() {
            let (pl, text) = lines.next().ok_or_else(|| {
                err(
                    last,
                    format!("patch {k}: the file ends after {m} of its 16 control points"),
                )
            })?;
            let xyz: Vec<f32> = text
                .split_whitespace()
                .map(str::parse)
                .collect::<Result<_, _>>()
                .map_err(|_| err(pl, format!("expected a point 'x y z', found '{text}'")))?;
            if xyz.len() != 3 {
                return Err(err(pl, format!("expected a point 'x y z', found '{text}'")));
            }
            *p = Vec3::new(xyz[0], xyz[1], xyz[2]);
            if !p.is_finite() {
                return Err(err(pl, format!("coordinate is not finite: '{text}'")));
            }
        }
        patches.push(BptPatch { line, points });
    }
    if let Some((line, _)) = lines.next() {
        return Err(err(
            line,
            format!("data after the {count} patches the first line declares"),
        ));
    }
    Ok(patches)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn patch_text(degrees: &str) -> String {
        let mut s = format!("{degrees}\n");
        for j in 0..4 {
            for i in 0..4 {
                s += &format!("{i} {j} 0\n");
            }
        }
        s
    }

    fn parse(text: &str) -> Result<Vec<BptPatch>, String> {
        parse_bpt(text, Path::new("t.bpt")).map_err(|e| e.to_string())
    }

    #[test]
    fn reads_patches_in_order() {
        let text = format!("2\n{}\n{}", patch_text("3 3"), patch_text("3 3"));
        let p = parse(&text).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].line, 2);
        assert_eq!(p[1].line, 20);
        assert_eq!(p[0].points[5], Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn malformed_files_name_the_line() {
        let one = patch_text("3 3");
        for (text, want) in [
            (String::new(), "line 1: empty file"),
            (
                "x\n".to_owned(),
                "line 1: expected the number of patches, found 'x'",
            ),
            ("0\n".to_owned(), "line 1: 0 patches declared"),
            (
                "99999999999\n".to_owned(),
                "line 1: 99999999999 patches declared; between 1 and",
            ),
            (
                format!("1\n{}", patch_text("2 3")),
                "line 2: patch 1: expected the degrees '3 3'",
            ),
            (
                format!("2\n{one}"),
                "line 18: the file ends after 1 patches; the first line declares 2",
            ),
            (
                format!("1\n{one}1 2 3\n"),
                "line 19: data after the 1 patches",
            ),
            (
                one.replacen("3 3\n", "1\n3 3\n", 1).replace("2 1 0", "2 1"),
                "line 9: expected a point 'x y z', found '2 1'",
            ),
            (
                format!("1\n{}", one.replace("2 1 0", "2 inf 0")),
                "line 9: coordinate is not finite",
            ),
            (
                format!("1\n{}", one.replace("2 1 0", "2 a 0")),
                "line 9: expected a point",
            ),
            (
                "1\n3 3\n0 0 0\n".to_owned(),
                "line 3: patch 1: the file ends after 1 of its 16",
            ),
        ] {
            let e = parse(&text).unwrap_err();
            assert!(e.contains(want), "{e} does not contain {want}");
            assert!(e.starts_with("t.bpt: "), "{e}");
        }
    }
}
