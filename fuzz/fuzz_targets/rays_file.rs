//! Ray files (`--rays-file`, `docs/rays-format.md`): any bytes either parse into as many
//! rays as the header declares (within the limit, the size matching exactly) that write
//! back to the same header, origins and directions, or are an error naming an offset inside
//! the file.
//!
//! The reader is compiled from its source file in the registry crate rather than through a
//! dependency on that crate, which would bring every backend (wgpu among them) into the
//! instrumented build; the module only needs `raybench-core` and `raybench-render`.
#![no_main]

#[allow(dead_code)]
#[path = "../../crates/registry/src/rays_file.rs"]
mod rays_file;

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    match rays_file::from_bytes(Path::new("fuzz.rays"), data) {
        Ok(f) => {
            let n = f.rays.len() as u64;
            assert!(n <= raybench_core::limits::MAX_EXPLICIT_RAYS);
            assert_eq!(
                data.len() as u64,
                rays_file::HEADER_BYTES + n * rays_file::RAY_BYTES
            );
            // Writing them back gives the same header and, ray by ray, the same origin and
            // direction (invalid rays keep them; only their interval is emptied).
            let again = rays_file::to_bytes(&f.rays, f.any_hit);
            assert_eq!(again.len(), data.len());
            assert_eq!(again[..24], data[..24]);
            for (a, b) in again[24..]
                .chunks_exact(32)
                .zip(data[24..].chunks_exact(32))
            {
                assert_eq!(a[..24], b[..24]);
            }
        }
        Err(e) => {
            if let Some(at) = e.offset {
                assert!(at <= data.len() as u64, "{e}");
            }
            assert!(!e.to_string().contains('\n'));
        }
    }
});
