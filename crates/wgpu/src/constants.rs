//! The constants the WGSL kernels share with Rust, written into the kernels' source from the
//! Rust definitions (never copied by hand): [`kernel_source`] prepends them to
//! the kernel files (`kernels/*.wgsl`), which declare none of them themselves. The
//! primitive kinds' numbers and pipeline-override flags come from
//! [`raybench_core::PrimitiveKind::ALL`], so a new kind is declared here by itself.

use crate::geo::bezier;
use crate::geo::heightfield::HF_STACK;
use crate::plan::BLOCK;
use crate::records::{
    EMITTER_BIT, HAS_INSTANCES, LIGHT_DIRECTIONAL, LIGHT_POINT, MAT_DIFFUSE, MAT_GLASS, MAT_MIRROR,
    NONE, RECORD, STACK_SIZE, WHITTED_STACK, kind_names, kind_number,
};
use raybench_core::integrator::{AMBIENT, DIMENSIONS_PER_BOUNCE, ROULETTE_DEPTH, SHADOW_SHORTEN};
use raybench_core::voxels::{EARLY_TERMINATION, SKIP_BLOCK};
use raybench_core::{FALLBACK_DEPTH, MAX_NEWTON_ITERATIONS, NO_HIT, PrimitiveKind, REGION_DEPTH};

/// The WGSL declarations of every shared constant, one `const` per line, each from the Rust
/// definition it names, then the pipeline-override constants of `Features` (`records.rs`)
/// (`override HAS_*: bool = true;`, every routine compiled unless a pipeline says otherwise).
#[must_use]
pub fn wgsl_constants() -> String {
    let kinds = PrimitiveKind::ALL.map(|k| {
        (
            kind_names(k).0,
            kind_number(k),
            "raybench_core::PrimitiveKind::index",
        )
    });
    // One row per shared constant: its WGSL name, its value, and the Rust it comes from.
    #[rustfmt::skip]
    let u32s: [(&str, u32, &str); 23] = [
        ("NO_HIT", NO_HIT, "raybench_core::NO_HIT"),
        ("MAT_DIFFUSE", MAT_DIFFUSE, "records.rs material kinds"),
        ("MAT_MIRROR", MAT_MIRROR, "records.rs material kinds"),
        ("MAT_GLASS", MAT_GLASS, "records.rs material kinds"),
        ("LIGHT_POINT", LIGHT_POINT, "records.rs light kinds"),
        ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL, "records.rs light kinds"),
        ("EMITTER_BIT", EMITTER_BIT, "records.rs prim_info"),
        ("INSTANCE_RECORD", RECORD, "records::RECORD, geo entries per instance"),
        ("NO_ENTRY", NONE, "records::NONE"),
        ("HF_STACK", HF_STACK, "geo::heightfield, the height-field walk's stack"),
        ("STACK_SIZE", STACK_SIZE, "BVH2 traversal stack"),
        ("WHITTED_STACK", WHITTED_STACK, "limits::MAX_DEPTH + 2"),
        ("ROULETTE_DEPTH", ROULETTE_DEPTH, "raybench_core::integrator"),
        ("DIMENSIONS_PER_BOUNCE", DIMENSIONS_PER_BOUNCE, "raybench_core::integrator"),
        ("BLOCK", BLOCK, "plan::BLOCK, pixels per block side"),
        ("SKIP_BLOCK", SKIP_BLOCK, "raybench_core::voxels::SKIP_BLOCK"),
        ("BEZIER_REGION_DEPTH", REGION_DEPTH, "raybench_geometry::bezier::REGION_DEPTH"),
        ("BEZIER_FALLBACK_DEPTH", FALLBACK_DEPTH, "raybench_geometry::bezier::FALLBACK_DEPTH"),
        ("BEZIER_NEWTON_ITERATIONS", MAX_NEWTON_ITERATIONS, "raybench_geometry::bezier"),
        ("BEZIER_STACK", bezier::STACK, "geo::bezier, 3 (REGION_DEPTH + FALLBACK_DEPTH) + 1"),
        ("BEZIER_DU", bezier::DU, "geo::bezier::DU layout"),
        ("BEZIER_DV", bezier::DV, "geo::bezier::DV layout"),
        ("BEZIER_BOXES", bezier::BOXES, "geo::bezier::BOXES layout"),
    ];
    #[rustfmt::skip]
    let f32s: [(&str, f32, &str); 7] = [
        ("AMBIENT", AMBIENT, "raybench_core::integrator"),
        ("SHADOW_SHORTEN", SHADOW_SHORTEN, "raybench_core::integrator"),
        ("MIN_POSITIVE", f32::MIN_POSITIVE, "f32::MIN_POSITIVE"),
        ("INV_PI", std::f32::consts::FRAC_1_PI, "std::f32::consts"),
        ("PI", std::f32::consts::PI, "std::f32::consts"),
        ("TAU", std::f32::consts::TAU, "std::f32::consts"),
        ("EARLY_TERMINATION", EARLY_TERMINATION, "raybench_core::voxels::EARLY_TERMINATION"),
    ];
    let ints = kinds
        .into_iter()
        .chain(u32s)
        .map(|(name, value, from)| (name, "u32", format!("{value}u"), from));
    // `{:e}` prints the shortest digits that round-trip, so WGSL parses the same f32.
    let floats = f32s.map(|(name, value, from)| (name, "f32", format!("{value:e}"), from));
    let mut out =
        String::from("// Generated from the Rust constants by crates/wgpu/src/constants.rs.\n");
    for (name, ty, value, from) in ints.chain(floats) {
        out += &format!("const {name}: {ty} = {value}; // {from}\n");
    }
    let flags = PrimitiveKind::ALL
        .iter()
        .filter_map(|&k| kind_names(k).1)
        .chain([HAS_INSTANCES]);
    for name in flags {
        out += &format!("override {name}: bool = true; // records::Features\n");
    }
    out
}

/// The WGSL files of the kernels (`kernels/`), in the order [`kernel_source`] joins them:
/// `main.wgsl` (bindings, traversal, shading, the entry points), then one file per
/// primitive kind or mode of its own. WGSL declarations may come in any order, so the files
/// call each other freely.
pub const KERNEL_FILES: [(&str, &str); 8] = [
    ("main.wgsl", include_str!("kernels/main.wgsl")),
    ("lights.wgsl", include_str!("kernels/lights.wgsl")),
    ("bilinear.wgsl", include_str!("kernels/bilinear.wgsl")),
    ("heightfield.wgsl", include_str!("kernels/heightfield.wgsl")),
    ("csg.wgsl", include_str!("kernels/csg.wgsl")),
    ("bezier.wgsl", include_str!("kernels/bezier.wgsl")),
    ("sdf.wgsl", include_str!("kernels/sdf.wgsl")),
    ("volume.wgsl", include_str!("kernels/volume.wgsl")),
];

/// The variable naming a folder to read the kernel files from at run time instead of the
/// copies compiled in (for editing the kernels without rebuilding:
/// `RAYBENCH_KERNELS_DIR=crates/wgpu/src/kernels`).
pub const KERNELS_DIR_VAR: &str = "RAYBENCH_KERNELS_DIR";

/// The complete WGSL source: the shared constants, then the [`KERNEL_FILES`] (read from
/// [`KERNELS_DIR_VAR`]'s folder when it is set; a file that cannot be read there is taken
/// from the compiled-in copy, with a warning).
#[must_use]
pub fn kernel_source() -> String {
    let dir = std::env::var_os(KERNELS_DIR_VAR).map(std::path::PathBuf::from);
    let mut s = wgsl_constants();
    for (name, text) in KERNEL_FILES {
        s += &format!("\n// ---- kernels/{name}\n");
        match dir.as_ref().map(|d| std::fs::read_to_string(d.join(name))) {
            Some(Ok(file)) => s += &file,
            Some(Err(e)) => {
                eprintln!(
                    "warning: {KERNELS_DIR_VAR}: cannot read {name} ({e}); using the built-in copy"
                );
                s += text;
            }
            None => s += text,
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The joined kernels parse and validate as WGSL (naga, wgpu's own front end), so that a
    /// broken kernel fails here, without an adapter, and not only in the GPU tests.
    #[test]
    fn the_kernels_are_valid_wgsl() {
        let module = naga::front::wgsl::parse_str(&kernel_source())
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&kernel_source())));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&kernel_source())));
    }

    #[test]
    fn every_constant_is_declared_once_and_parses_back() {
        let kernels: String = KERNEL_FILES.iter().map(|(_, text)| *text).collect();
        for line in wgsl_constants().lines().skip(1) {
            let (keyword, rest) = line.split_once(' ').expect("a declaration");
            assert!(keyword == "const" || keyword == "override", "{line}");
            let name = rest.split(':').next().expect("a declaration");
            assert!(
                !kernels.contains(&format!("const {name}:"))
                    && !kernels.contains(&format!("override {name}:")),
                "the kernels declare {name} by hand; it comes from constants.rs"
            );
            if keyword == "override" {
                assert!(line.contains(": bool = true;"), "{line}");
                continue;
            }
            let value = line
                .split('=')
                .nth(1)
                .unwrap()
                .split(';')
                .next()
                .unwrap()
                .trim();
            if let Some(v) = value.strip_suffix('u') {
                v.parse::<u32>().expect("a u32 literal");
            } else {
                // The float literal reads back to the Rust value's bits.
                let f: f32 = value.parse().expect("an f32 literal");
                assert!(f.is_finite() && f != 0.0, "{line}");
            }
        }
        assert!(wgsl_constants().contains(&format!("const AMBIENT: f32 = {:e};", AMBIENT)));
    }
}
