//! In-memory entry points for the fuzz targets (`fuzz/`) and the regression tests: each
//! wraps the code path a scene's file goes through, with the file's bytes given instead of
//! read, and a memory budget of the caller's choosing. Nothing here parses or decodes on
//! its own. Not a stable interface.

use crate::budget::Reservation;
use crate::error::LoadError;
use crate::obj::MeshData;
use crate::texture::{ImageSource, TextureRef};
use raybench_core::{Texture, Vec3, Wrap};
use std::path::Path;

/// The most texels an environment map may have (the loader refuses larger ones from their
/// header).
pub const MAX_ENVIRONMENT_TEXELS: u64 = crate::format::background::MAX_ENVIRONMENT_TEXELS;

/// The memory budget's estimate per environment-map texel, in bytes: a map of `n` texels
/// loads only when `n` times this fits in the budget.
pub const ENVIRONMENT_TEXEL_BYTES: u64 = crate::budget::ENVIRONMENT_TEXEL_BYTES_ESTIMATE;

/// The memory budget's estimate per texture texel, in bytes: a texture of `n` texels is
/// decoded only when `n` times this fits in the budget.
pub const TEXTURE_TEXEL_BYTES: u64 = crate::budget::TEXEL_BYTES_ESTIMATE;

/// Parses the OBJ bytes `obj` (`path` names the file; its folder holds the material
/// libraries and textures) as [`crate::load_obj_file`] does, with every `mtllib` it names
/// read as `mtl`: the same check of its statements, `tobj`'s MTL parser and
/// the mapping of MTL materials and texture statements onto raybench's. Bytes that are
/// not UTF-8 (after an optional byte-order mark) are an unreadable library: no materials.
///
/// # Errors
/// As [`crate::load_obj_file`], less the file errors of the OBJ file.
pub fn load_obj_with_mtl(obj: &[u8], mtl: &[u8], path: &Path) -> Result<MeshData, LoadError> {
    crate::obj::parse_obj_with_mtl(obj, path, |mtl_path| {
        crate::io::text_from_bytes(mtl_path, mtl.to_vec()).ok()
    })
}

/// Decodes an environment map held in memory as a scene's `background = { map = ... }`
/// does (the extension of `path`, `.exr` or `.hdr`, chooses the format), against a memory
/// budget of `budget_bytes`: the width, the height, the linear RGB texels row by row from
/// the top (negative components read as 0), and whether any texel was negative.
///
/// # Errors
/// As the scene loader reports a map it cannot use: another extension, an undecodable or
/// empty image, more than [`MAX_ENVIRONMENT_TEXELS`] texels, a texel that is not finite,
/// or ([`LoadError::OverBudget`]) a map over the budget.
pub fn read_environment_map(
    bytes: &[u8],
    path: &Path,
    budget_bytes: u64,
) -> Result<(u32, u32, Vec<Vec3>, bool), LoadError> {
    let mut budget = Reservation::with_limit(budget_bytes);
    crate::format::background::read_map(path, Some(bytes), &mut budget, "fuzz")
}

/// Decodes a texture image held in memory (PNG or JPEG, its format guessed from its bytes)
/// as a mesh file's material texture is decoded when its scene is built, with wrap modes
/// `wrap`, against a memory budget of `budget_bytes`. The inner error is the warning's
/// reason when the scene could not use the texture (its material keeps its flat colour).
///
/// # Errors
/// [`LoadError::OverBudget`] when the image's header declares more texels than the budget
/// holds.
pub fn decode_texture(
    bytes: &[u8],
    wrap: [Wrap; 2],
    budget_bytes: u64,
) -> Result<Result<Texture, String>, LoadError> {
    let tex = TextureRef {
        name: "fuzz".into(),
        source: ImageSource::Bytes {
            key: "fuzz".into(),
            bytes: bytes.into(),
        },
        wrap,
    };
    let mut budget = Reservation::with_limit(budget_bytes);
    crate::texture::decode(&tex, &mut budget, "fuzz")
}
