//! The one step plotters does not take: SVG `<title>` tooltips. A point, a bar, a stub or a
//! fitted line is drawn between two marks (text elements whose content starts with
//! [`MARK`], a private-use character no label carries: [`plain`] strips it); once plotters
//! has written the document, [`finish`] turns each opening mark into `<g><title>…</title>`
//! and each closing one into `</g>`, and puts the chart's own title and role after a header
//! of its own. Nothing else of plotters' output is touched.
//!
//! Worth its few lines: the report's HTML page embeds each chart as a live SVG document so
//! that hovering a point shows its series and values, and a backend that did not run shows
//! why only there.

use super::escape;

/// The first character of a mark's text: one of Unicode's private-use characters.
const MARK: char = '\u{E000}';

/// `s` without [`MARK`], so that no label can pass for a mark.
pub(super) fn plain(s: &str) -> String {
    s.replace(MARK, "")
}

/// The tooltips of one chart, in the order their marks are drawn.
#[derive(Debug, Default)]
pub(super) struct Tips {
    /// Each group's tooltip text, unescaped.
    titles: Vec<String>,
}

impl Tips {
    /// The text of a mark that opens a group with tooltip `title`.
    pub(super) fn open(&mut self, title: String) -> String {
        self.titles.push(plain(&title));
        format!("{MARK}{}", self.titles.len() - 1)
    }

    /// The text of a mark that closes the group opened last.
    pub(super) fn close() -> String {
        MARK.to_string()
    }
}

/// plotters' SVG document `body` of a chart `width` x `height` titled `title`, its marks
/// turned into groups with tooltips.
///
/// # Errors
/// When `body` is not plotters' SVG (no header line, or a mark that names no tooltip).
pub(super) fn finish(
    body: &str,
    (width, height): (u32, u32),
    title: &str,
    tips: &Tips,
) -> Result<String, String> {
    // plotters writes its `<svg ...>` header on the first line; ours says the same with the
    // namespace first, and the chart's title for screen readers and tooltips.
    let rest = match body.split_once('\n') {
        Some((header, rest)) if header.starts_with("<svg ") => rest,
        _ => return Err("the chart's SVG has no header line".into()),
    };
    let mut out = String::with_capacity(body.len() + tips.titles.len() * 64);
    out.push_str(&format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 {width} {height}\" \
         width=\"{width}\" height=\"{height}\" role=\"img\">\n<title>{}</title>\n",
        escape(&plain(title))
    ));
    // plotters writes a text element on three lines: its tag, its escaped text, `</text>`.
    let lines: Vec<&str> = rest.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let mark = lines
            .get(i + 1)
            .and_then(|l| l.strip_prefix(MARK))
            .filter(|_| lines[i].starts_with("<text ") && lines.get(i + 2) == Some(&"</text>"));
        match mark {
            Some("") => {
                out.push_str("</g>\n");
                i += 3;
            }
            Some(n) => {
                let title = n
                    .parse::<usize>()
                    .ok()
                    .and_then(|n| tips.titles.get(n))
                    .ok_or_else(|| format!("a chart's tooltip mark {n:?} names no tooltip"))?;
                out.push_str("<g><title>");
                out.push_str(&escape(title));
                out.push_str("</title>\n");
                i += 3;
            }
            None => {
                out.push_str(lines[i]);
                out.push('\n');
                i += 1;
            }
        }
    }
    Ok(out)
}
