use raybench_core::{Ray, Vec3, limits};
use raybench_registry::rays_file::*;
use std::path::Path;

fn rays() -> Vec<Ray> {
    vec![
        Ray::new(Vec3::new(1.0, -2.0, 3.5), Vec3::new(0.0, 0.6, -0.8)),
        Ray::with_interval(Vec3::ZERO, Vec3::X, 0.25, 7.0),
        // Not valid: kept as the empty interval it was given.
        Ray::with_interval(Vec3::ZERO, Vec3::ZERO, 0.0, 1.0),
        Ray::with_interval(
            Vec3::new(-0.0, f32::MIN_POSITIVE, 1e18),
            Vec3::new(1e-3, -3.0, 2.0),
            1e-30,
            f32::MAX,
        ),
    ]
}

/// A ray's stored fields as bits (an invalid ray's cached shear is NaN, so rays are
/// compared by what the file holds).
fn bits(r: &Ray) -> ([u32; 3], [u32; 3], u32, u32) {
    (
        r.origin.to_array().map(f32::to_bits),
        r.dir.to_array().map(f32::to_bits),
        r.t_min.to_bits(),
        r.t_max.to_bits(),
    )
}

fn path() -> &'static Path {
    Path::new("test.rays")
}

#[test]
fn rays_round_trip_bit_for_bit() {
    for any_hit in [false, true] {
        let bytes = to_bytes(&rays(), any_hit);
        assert_eq!(bytes.len() as u64, HEADER_BYTES + 4 * RAY_BYTES);
        let back = from_bytes(path(), &bytes).unwrap();
        assert_eq!(back.any_hit, any_hit);
        assert_eq!(back.rays.len(), 4);
        for (a, b) in rays().iter().zip(&back.rays) {
            assert_eq!(bits(a), bits(b));
        }
    }
    assert_eq!(from_bytes(path(), &to_bytes(&[], false)).unwrap().rays, []);
}

#[test]
fn the_header_is_as_documented() {
    let h = header(0x0102_0304_0506_0708, true);
    assert_eq!(&h[..8], b"RAYBENCH");
    assert_eq!(h[8..12], [1, 0, 0, 0]);
    assert_eq!(h[12..20], [8, 7, 6, 5, 4, 3, 2, 1]);
    assert_eq!(h[20..24], [1, 0, 0, 0]);
    let one = to_bytes(&[Ray::with_interval(Vec3::X, Vec3::Y, 0.5, 2.0)], false);
    assert_eq!(one[24..28], 1.0f32.to_le_bytes());
    assert_eq!(one[40..44], 1.0f32.to_le_bytes());
    assert_eq!(one[48..52], 0.5f32.to_le_bytes());
    assert_eq!(one[52..56], 2.0f32.to_le_bytes());
}

/// Every truncation, and every extra byte, is an error naming an offset, never a panic.
#[test]
fn every_truncation_is_an_error() {
    let bytes = to_bytes(&rays(), true);
    for n in 0..bytes.len() {
        let e = from_bytes(path(), &bytes[..n]).unwrap_err();
        assert!(e.offset.is_some(), "{e}");
        assert!(e.to_string().starts_with("test.rays: byte "), "{e}");
    }
    let mut longer = bytes.clone();
    longer.push(0);
    let e = from_bytes(path(), &longer).unwrap_err();
    assert!(e.cause.contains("1 bytes after"), "{e}");
    let e = from_bytes(path(), &bytes[..HEADER_BYTES as usize + 40]).unwrap_err();
    assert!(e.cause.contains("inside record 1"), "{e}");
}

#[test]
fn bad_headers_are_refused() {
    let good = to_bytes(&rays(), false);
    let with = |at: usize, patch: &[u8]| {
        let mut b = good.clone();
        b[at..at + patch.len()].copy_from_slice(patch);
        from_bytes(path(), &b).unwrap_err()
    };
    let e = with(0, b"RAYBENCX");
    assert_eq!(e.offset, Some(0));
    assert!(e.cause.contains("not a ray file"), "{e}");
    let e = with(8, &2u32.to_le_bytes());
    assert_eq!(e.offset, Some(8));
    assert!(e.cause.contains("version 2"), "{e}");
    for flags in [2u32, 0x8000_0000, 3] {
        let e = with(20, &flags.to_le_bytes());
        assert_eq!(e.offset, Some(20));
        assert!(e.cause.contains("unknown flag bits"), "{e}");
    }
    // A count beyond the limit (or one whose size would overflow) is refused from the
    // header, before any allocation.
    for count in [limits::MAX_EXPLICIT_RAYS + 1, u64::MAX] {
        let e = with(12, &count.to_le_bytes());
        assert_eq!(e.offset, Some(12));
        assert!(e.cause.contains("exceed the limit"), "{e}");
    }
    // A count that disagrees with the size.
    let e = with(12, &5u64.to_le_bytes());
    assert!(e.cause.contains("the header says 5 rays"), "{e}");
    let e = with(12, &3u64.to_le_bytes());
    assert!(e.cause.contains("32 bytes after"), "{e}");
}

/// Seeded random byte strings and random single-byte corruptions: an answer or an
/// error, never a panic; a corrupted file that still parses has the right size.
/// The seeds of the `rays_file` fuzz target (`fuzz/seeds/rays_file/`) are valid files.
#[test]
fn fuzz_seeds_parse() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/rays_file");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        let f = read(&p).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(std::fs::read(&p).unwrap(), to_bytes(&f.rays, f.any_hit));
        n += 1;
    }
    assert!(n >= 2);
}

#[test]
fn random_bytes_never_panic() {
    let good = to_bytes(&rays(), true);
    let mut state = 0x1234_5678u32;
    let mut next = || {
        state = raybench_core::sampling::pcg3d([state, 7, 11])[0];
        state
    };
    for _ in 0..2000 {
        let mut b = good.clone();
        let at = next() as usize % b.len();
        b[at] = next() as u8;
        if let Ok(f) = from_bytes(path(), &b) {
            assert_eq!(f.rays.len(), 4);
        }
        let n = next() as usize % 80;
        let noise: Vec<u8> = (0..n).map(|_| next() as u8).collect();
        assert!(from_bytes(path(), &noise).is_err());
    }
}

#[test]
fn files_round_trip_and_name_themselves() {
    let dir = std::env::temp_dir().join(format!("raybench-rays-file-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("set.rays");
    write(&p, &rays(), true).unwrap();
    let back = read(&p).unwrap();
    assert!(back.any_hit);
    let same = back
        .rays
        .iter()
        .zip(&rays())
        .all(|(a, b)| bits(a) == bits(b));
    assert!(same && back.rays.len() == 4);
    std::fs::write(&p, &to_bytes(&rays(), true)[..30]).unwrap();
    let e = read(&p).unwrap_err();
    assert!(
        e.to_string()
            .starts_with(&format!("{}: byte 30:", p.display())),
        "{e}"
    );
    let e = read(&dir.join("absent.rays")).unwrap_err();
    assert!(e.to_string().contains("absent.rays"), "{e}");
    assert!(read(&dir).unwrap_err().cause.contains("not a regular file"));
    let _ = std::fs::remove_dir_all(&dir);
}
