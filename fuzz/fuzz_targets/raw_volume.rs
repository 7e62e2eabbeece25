//! The raw volume loader: a 13-byte header (three little-endian u32 dims and a format
//! byte: 0 u8, 1 u16, 2 f32) then the samples. Any input either gives a valid volume or
//! is an error, and huge declared dims are refused before anything is allocated.
#![no_main]

use libfuzzer_sys::fuzz_target;
use raybench_core::{Affine3A, TransferFunction, Vec3, Volume, VolumeData, VolumeParams};
use raybench_scene::samples::{SampleFormat, decode_raw};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((header, samples)) = data.split_first_chunk::<13>() else {
        return;
    };
    let dim = |i: usize| u32::from_le_bytes(header[4 * i..4 * i + 4].try_into().unwrap());
    let dims = [dim(0), dim(1), dim(2)];
    let format = match header[12] % 3 {
        0 => SampleFormat::U8,
        1 => SampleFormat::U16,
        _ => SampleFormat::F32,
    };
    let Ok(count) = raybench_core::voxels::check_volume_dims(dims) else {
        return;
    };
    let path = Path::new("fuzz.raw");
    let max = raybench_core::limits::MAX_VOLUME_VOXELS;
    let Ok(raw) = decode_raw(samples, count, format, max, path) else {
        return;
    };
    let volume = Volume::new(
        dims,
        Vec3::ONE,
        VolumeData::from(raw),
        Affine3A::IDENTITY,
        TransferFunction::ramp(10.0),
        VolumeParams::default(),
    );
    if let Ok(v) = volume {
        assert_eq!(v.dims(), dims);
    }
});
