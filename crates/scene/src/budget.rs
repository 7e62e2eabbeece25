//! The memory budget: a scene's memory is estimated from its declared sizes (generator
//! arguments, `tessellate`, voxel and vertex counts, a mesh file's triangle count) before
//! the large allocations happen, and a scene over the budget is refused with the estimate
//! and how to raise the limit, rather than left to exhaust the machine.
//!
//! The budget is, in order: the command line's `--memory-limit`
//! ([`set_memory_limit`]), the environment variable [`MEMORY_LIMIT_ENV`], or
//! [`DEFAULT_SHARE`] of the memory the system reports available (`MemAvailable` in
//! `/proc/meminfo`; no limit where that file does not exist).

use crate::error::LoadError;
use raybench_core::Scene;
use raybench_core::limits::{
    HEIGHT_FIELD_VERTEX_BYTES_ESTIMATE, PRIMITIVE_BYTES_ESTIMATE, VOXEL_BYTES_ESTIMATE,
};
use std::sync::OnceLock;

/// The environment variable that sets the memory budget: a size such as `8G`, `512M` or
/// `1000000` (bytes; suffixes K, M, G, T are powers of 1024), or `none` for no limit.
pub const MEMORY_LIMIT_ENV: &str = "RAYBENCH_MEMORY_LIMIT";

/// The share of the available memory the default budget grants: the machine may be
/// shared, and the estimates are estimates.
pub const DEFAULT_SHARE: f64 = 0.5;

/// A limit on the memory a scene may take, and where it comes from (for messages).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryBudget {
    /// Bytes, or `None` for no limit.
    pub bytes: Option<u64>,
    /// Where the limit comes from: `--memory-limit`, the environment variable, or the
    /// available memory.
    pub origin: String,
}

static COMMAND_LINE: OnceLock<MemoryBudget> = OnceLock::new();

/// Sets the process's budget from the command line's `--memory-limit` (`None`: no limit);
/// it takes precedence over [`MEMORY_LIMIT_ENV`]. Only the first call counts.
pub fn set_memory_limit(bytes: Option<u64>) {
    let _ = COMMAND_LINE.set(MemoryBudget {
        bytes,
        origin: "--memory-limit".into(),
    });
}

/// Parses a size: `none`, or a whole number of bytes with an optional suffix K, M, G or T
/// (powers of 1024, an optional trailing `B` or `iB`, any case).
///
/// # Errors
/// A sentence saying what is wrong.
pub fn parse_size(text: &str) -> Result<Option<u64>, String> {
    let t = text.trim();
    if t.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let upper = t.to_ascii_uppercase();
    let body = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (digits, shift) = match body.char_indices().last() {
        Some((i, 'K')) => (&body[..i], 10),
        Some((i, 'M')) => (&body[..i], 20),
        Some((i, 'G')) => (&body[..i], 30),
        Some((i, 'T')) => (&body[..i], 40),
        _ => (body, 0),
    };
    let bad = || format!("'{text}' is not a size (for example 8G, 512M or none)");
    let n: u64 = digits.trim().parse().map_err(|_| bad())?;
    let bytes = n.checked_mul(1 << shift).ok_or_else(bad)?;
    if bytes == 0 {
        return Err(format!(
            "'{text}': the memory limit must be above 0 (or none)"
        ));
    }
    Ok(Some(bytes))
}

/// `MemAvailable` of `/proc/meminfo`, in bytes; `None` where that file does not exist.
#[must_use]
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// `bytes` for people: `1.5 GiB`.
#[must_use]
pub fn human_bytes(bytes: u64) -> String {
    let units = ["bytes", "KiB", "MiB", "GiB", "TiB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < units.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{v:.1} {}", units[unit])
    }
}

impl MemoryBudget {
    /// Whether the user set this budget (`--memory-limit` or [`MEMORY_LIMIT_ENV`]) rather
    /// than it being the default share of the available memory: a user's limit also lifts
    /// the check on images that decode to far more than their files hold
    /// ([`crate::samples::check_expansion`]).
    #[must_use]
    pub fn is_set_by_user(&self) -> bool {
        self.origin == "--memory-limit" || self.origin == MEMORY_LIMIT_ENV
    }

    /// The budget in force ([`set_memory_limit`], else [`MEMORY_LIMIT_ENV`], else
    /// [`DEFAULT_SHARE`] of the available memory, else none).
    ///
    /// # Errors
    /// [`LoadError::Parse`] naming the environment variable when its value is not a size.
    pub fn current() -> Result<Self, LoadError> {
        if let Some(b) = COMMAND_LINE.get() {
            return Ok(b.clone());
        }
        if let Some(v) = std::env::var_os(MEMORY_LIMIT_ENV).filter(|v| !v.is_empty()) {
            let text = v.to_string_lossy();
            let bytes = parse_size(&text).map_err(|message| LoadError::Parse {
                path: MEMORY_LIMIT_ENV.into(),
                message,
            })?;
            return Ok(Self {
                bytes,
                origin: MEMORY_LIMIT_ENV.into(),
            });
        }
        Ok(match available_memory() {
            Some(avail) => Self {
                bytes: Some((avail as f64 * DEFAULT_SHARE) as u64),
                origin: format!(
                    "{:.0}% of the {} available",
                    DEFAULT_SHARE * 100.0,
                    human_bytes(avail)
                ),
            },
            None => Self {
                bytes: None,
                origin: "no limit: the available memory is unknown".into(),
            },
        })
    }
}

/// Estimated bytes of `scene` flattened ([`raybench_core::flatten`]): every primitive of
/// the flattened scene stored and under an acceleration structure.
#[must_use]
pub fn flattened_bytes_estimate(scene: &Scene) -> u64 {
    (scene.geometry.total_len() as u64).saturating_mul(PRIMITIVE_BYTES_ESTIMATE)
}

/// `scene` flattened ([`raybench_core::flatten`]: its instances' primitives carried to world
/// space and stored flat, ids unchanged) once its flattened primitives are checked against
/// the memory budget: how `--flatten` and the report's `instancing` experiment flatten.
///
/// # Errors
/// [`LoadError::OverBudget`] with the estimate and how to raise the budget, before anything
/// is allocated; [`LoadError::Scene`] when a primitive cannot be flattened exactly.
pub fn flatten_within_budget(scene: &Scene) -> Result<Scene, LoadError> {
    let context = format!("{} flattened", scene.name);
    if scene.geometry.has_instances() {
        Reservation::new()?.reserve(
            Holds::Primitives(scene.geometry.total_len() as u64),
            &context,
        )?;
    }
    raybench_core::flatten(scene).map_err(|cause| LoadError::Scene { context, cause })
}

/// A scene's estimated memory so far, against the budget.
#[derive(Debug)]
pub(crate) struct Reservation {
    budget: MemoryBudget,
    used: u64,
}

/// What a part of a scene holds, for [`Reservation::reserve`].
#[derive(Clone, Copy, Debug)]
pub(crate) enum Holds {
    /// Primitives (triangles, spheres, patches).
    Primitives(u64),
    /// Height-field vertices.
    Vertices(u64),
    /// Volume voxels.
    Voxels(u64),
    /// Texels of an environment map.
    EnvironmentTexels(u64),
    /// Texture texels.
    Texels(u64),
    /// Instances (their records and top-level tree: the meshes they place are counted once,
    /// as the primitives of their objects).
    Instances(u64),
}

/// Bytes per environment-map texel while it loads: the decoded RGBA f32 image (16), the
/// linear RGB copy (12) and the sampling table (8).
pub(crate) const ENVIRONMENT_TEXEL_BYTES_ESTIMATE: u64 = 36;
/// Estimated memory per texture texel, in bytes: 12 for the linear RGB texel the scene
/// keeps, plus the decoding's transient 8-bit RGBA image and RGB copy (7).
pub(crate) const TEXEL_BYTES_ESTIMATE: u64 = 19;
/// Estimated memory per instance, in bytes: its record (an [`raybench_core::Instance`]:
/// three transforms and a box), its material override and object record, and its share of
/// a two-level structure's top-level tree (the 230 bytes of `limits::MAX_INSTANCES`,
/// rounded up).
pub(crate) const INSTANCE_BYTES_ESTIMATE: u64 = 256;

impl Holds {
    /// The estimate in bytes, and the same in words.
    fn estimate(self) -> (u64, String) {
        let (n, each, what) = match self {
            Self::Primitives(n) => (
                n,
                PRIMITIVE_BYTES_ESTIMATE,
                "primitives and their acceleration structure",
            ),
            Self::Vertices(n) => (
                n,
                HEIGHT_FIELD_VERTEX_BYTES_ESTIMATE,
                "height-field vertices",
            ),
            Self::Voxels(n) => (n, VOXEL_BYTES_ESTIMATE, "voxels"),
            Self::EnvironmentTexels(n) => (
                n,
                ENVIRONMENT_TEXEL_BYTES_ESTIMATE,
                "environment-map texels",
            ),
            Self::Texels(n) => (n, TEXEL_BYTES_ESTIMATE, "texture texels"),
            Self::Instances(n) => (n, INSTANCE_BYTES_ESTIMATE, "instances"),
        };
        (
            n.saturating_mul(each),
            format!("{n} {what}, about {each} bytes each"),
        )
    }
}

impl Reservation {
    /// A reservation against a budget of `bytes` (for tests of what a budget refuses, and
    /// the fuzz targets).
    pub(crate) fn with_limit(bytes: u64) -> Self {
        Self {
            budget: MemoryBudget {
                bytes: Some(bytes),
                origin: "test".into(),
            },
            used: 0,
        }
    }

    /// Whether the user set the budget ([`MemoryBudget::is_set_by_user`]).
    pub(crate) fn is_set_by_user(&self) -> bool {
        self.budget.is_set_by_user()
    }

    /// A reservation against a budget of `bytes` that the user set (for tests of what a
    /// user's limit allows).
    #[cfg(test)]
    pub(crate) fn with_user_limit(bytes: u64) -> Self {
        Self {
            budget: MemoryBudget {
                bytes: Some(bytes),
                origin: MEMORY_LIMIT_ENV.into(),
            },
            used: 0,
        }
    }

    /// A reservation against the budget in force ([`MemoryBudget::current`]).
    pub(crate) fn new() -> Result<Self, LoadError> {
        Ok(Self {
            budget: MemoryBudget::current()?,
            used: 0,
        })
    }

    /// Adds what `holds` will take, before it is allocated; `context` names the scene and
    /// the part (`scene.toml: line 7: object 2 (bezier)`).
    ///
    /// # Errors
    /// [`LoadError::OverBudget`] with the estimate, the budget and how to raise it.
    pub(crate) fn reserve(&mut self, holds: Holds, context: &str) -> Result<(), LoadError> {
        let (bytes, words) = holds.estimate();
        let total = self.used.saturating_add(bytes);
        if let Some(limit) = self.budget.bytes
            && total > limit
        {
            let so_far = if self.used > 0 {
                format!(", {} with the rest of the scene", human_bytes(total))
            } else {
                String::new()
            };
            return Err(LoadError::OverBudget {
                context: context.to_owned(),
                message: format!(
                    "needs about {} for {words}{so_far}, over the memory budget of {} ({}); \
                     raise it with --memory-limit SIZE or {MEMORY_LIMIT_ENV}=SIZE (e.g. 32G, \
                     or none)",
                    human_bytes(bytes),
                    human_bytes(limit),
                    self.budget.origin
                ),
            });
        }
        self.used = total;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("8G"), Ok(Some(8 << 30)));
        assert_eq!(parse_size("512m"), Ok(Some(512 << 20)));
        assert_eq!(parse_size("2GiB"), Ok(Some(2 << 30)));
        assert_eq!(parse_size("1000"), Ok(Some(1000)));
        assert_eq!(parse_size("none"), Ok(None));
        for bad in ["", "G", "-1G", "0", "1.5G", "99999999999T", "8X"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
        assert_eq!(human_bytes(3 << 29), "1.5 GiB");
    }

    #[test]
    fn reservations_add_up() {
        let mut r = Reservation {
            budget: MemoryBudget {
                bytes: Some(10 * PRIMITIVE_BYTES_ESTIMATE),
                origin: "test".into(),
            },
            used: 0,
        };
        r.reserve(Holds::Primitives(6), "a").unwrap();
        let e = r
            .reserve(Holds::Primitives(6), "b")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b: needs about"), "{e}");
        assert!(
            e.contains("with the rest of the scene") && e.contains("--memory-limit"),
            "{e}"
        );
        r.reserve(Holds::Primitives(4), "c").unwrap();
    }

    /// Instances count their records only (their meshes are primitives of their objects,
    /// counted once): a million instances of a large mesh are a quarter of a gigabyte.
    #[test]
    fn instances_count_their_records() {
        let mut r = Reservation::with_limit(10 * INSTANCE_BYTES_ESTIMATE);
        r.reserve(Holds::Instances(10), "a").unwrap();
        let e = r.reserve(Holds::Instances(1), "b").unwrap_err().to_string();
        assert!(e.contains("1 instances, about 256 bytes each"), "{e}");
    }
}
