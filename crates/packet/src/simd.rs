//! The lane vectors the kernels are written in, one implementation per instruction set.
//!
//! Kernels are generic over [`Lanes`] and marked `#[inline(always)]`; each instruction set
//! has one entry function with `#[target_feature]` that instantiates them, so the same
//! source compiles to AVX2 (8 lanes), SSE4.1 (4 lanes) and portable code (4 lanes of plain
//! `f32`, which is also what runs on non-x86 targets). The operations are the IEEE ones,
//! lane by lane: no approximate reciprocals, no fused multiply-add.
//!
//! `min` and `max` follow the x86 rule (`a < b ? a : b`): when either operand is NaN the
//! *second* is returned. The box tests rely on that to leave an axis unconstrained when
//! `0 * inf` makes its distance NaN (see `raybench_geometry::SlabRay`).

use raybench_geometry::Ray;

/// A vector of `W` `f32` lanes and its lane masks.
pub(crate) trait Lanes: Copy + Send + Sync + 'static {
    /// Lanes per vector.
    const W: usize;
    /// The lanes of the single-ray code, which tests the 8 children of a BVH8 node or up
    /// to 8 leaf triangles at once (itself, except for 16-lane AVX-512, which uses AVX2
    /// there).
    type Single: Lanes;
    /// Four lanes, for the leaf blocks of four triangles (itself for four-lane sets, SSE4.1
    /// under AVX2 and AVX-512).
    type Narrow: Lanes;
    /// `W` floats.
    type V: Copy;
    /// `W` lane flags.
    type M: Copy;

    fn splat(x: f32) -> Self::V;
    /// The first `W` elements of `s` (which must have at least `W`).
    fn load(s: &[f32]) -> Self::V;
    /// Writes the lanes to the first `W` elements of `out`.
    fn store(v: Self::V, out: &mut [f32]);
    fn add(a: Self::V, b: Self::V) -> Self::V;
    fn sub(a: Self::V, b: Self::V) -> Self::V;
    fn mul(a: Self::V, b: Self::V) -> Self::V;
    fn div(a: Self::V, b: Self::V) -> Self::V;
    /// `a < b ? a : b` per lane.
    fn min(a: Self::V, b: Self::V) -> Self::V;
    /// `a > b ? a : b` per lane.
    fn max(a: Self::V, b: Self::V) -> Self::V;
    /// Ordered comparisons: false where either lane is NaN.
    fn lt(a: Self::V, b: Self::V) -> Self::M;
    fn le(a: Self::V, b: Self::V) -> Self::M;
    fn gt(a: Self::V, b: Self::V) -> Self::M;
    fn eq(a: Self::V, b: Self::V) -> Self::M;
    fn and(a: Self::M, b: Self::M) -> Self::M;
    fn or(a: Self::M, b: Self::M) -> Self::M;
    /// `!a & b`.
    fn andnot(a: Self::M, b: Self::M) -> Self::M;
    /// `m ? a : b` per lane.
    fn select(m: Self::M, a: Self::V, b: Self::V) -> Self::V;
    /// Bit `i` set when lane `i` is set.
    fn bits(m: Self::M) -> u32;
    /// The mask whose lane `i` is bit `i` of `bits`.
    fn mask(bits: u32) -> Self::M;
    /// The eight columns of the `W x 8` matrix whose row `i` is `rows[i]` (`rows` holds at
    /// least `W`): vector `j` holds element `j` of every row. It turns eight consecutive
    /// fields of `W` rays ([`ray_rows`]) into lanes with vector loads and shuffles; storing
    /// the fields one float at a time and loading them back as vectors stalls every load
    /// on store forwarding.
    fn columns8(rows: &[&[f32; 8]]) -> [Self::V; 8];
}

/// The first [`Ray::FLOATS`] floats of `ray` as one array (`origin`, `dir`, `inv_dir`,
/// `t_min`, `t_max`, `shear`).
#[allow(unsafe_code)]
#[inline(always)]
pub(crate) fn ray_floats(ray: &Ray) -> &[f32; Ray::FLOATS] {
    const {
        assert!(std::mem::size_of::<Ray>() >= 4 * Ray::FLOATS);
        assert!(std::mem::offset_of!(Ray, shear) + 12 == 4 * Ray::FLOATS);
    }
    // SAFETY: `Ray` is `repr(C)` and starts with `Ray::FLOATS` `f32` fields and no padding
    // (asserted where it is declared, and its size above), so the array covers initialised
    // floats inside the ray, aligned as `f32`, and borrows it for its own lifetime.
    unsafe { &*std::ptr::from_ref(ray).cast::<[f32; Ray::FLOATS]>() }
}

/// For each lane of a packet vector, its ray's floats `0..8` (`origin`, `dir`, `inv_dir.x`,
/// `inv_dir.y`) and `6..14` (`inv_dir`, `t_min`, `t_max`, `shear`), the rows
/// [`Lanes::columns8`] transposes; lanes past the end of `rays` repeat its last ray.
#[inline(always)]
pub(crate) fn ray_rows<L: Lanes>(rays: &[Ray]) -> ([&[f32; 8]; 16], [&[f32; 8]; 16]) {
    let last = ray_floats(&rays[rays.len() - 1]);
    let (mut head, mut tail) = ([first8(last); 16], [last8(last); 16]);
    for (lane, ray) in rays.iter().take(L::W).enumerate() {
        let f = ray_floats(ray);
        (head[lane], tail[lane]) = (first8(f), last8(f));
    }
    (head, tail)
}

/// Floats `0..8` of a ray's [`ray_floats`].
#[inline(always)]
fn first8(f: &[f32; Ray::FLOATS]) -> &[f32; 8] {
    f.first_chunk().expect("a ray has more than eight floats")
}

/// Floats `6..14` of a ray's [`ray_floats`].
#[inline(always)]
fn last8(f: &[f32; Ray::FLOATS]) -> &[f32; 8] {
    f.last_chunk().expect("a ray has more than eight floats")
}

/// Portable lanes: four plain `f32`s, compiled for the baseline target.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

impl Lanes for Portable {
    const W: usize = 4;
    type Single = Self;
    type Narrow = Self;
    type V = [f32; 4];
    type M = [bool; 4];

    #[inline(always)]
    fn splat(x: f32) -> Self::V {
        [x; 4]
    }
    #[inline(always)]
    fn load(s: &[f32]) -> Self::V {
        [s[0], s[1], s[2], s[3]]
    }
    #[inline(always)]
    fn store(v: Self::V, out: &mut [f32]) {
        out[..4].copy_from_slice(&v);
    }
    #[inline(always)]
    fn add(a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] + b[i])
    }
    #[inline(always)]
    fn sub(a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] - b[i])
    }
    #[inline(always)]
    fn mul(a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] * b[i])
    }
    #[inline(always)]
    fn div(a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| a[i] / b[i])
    }
    #[inline(always)]
    fn min(a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| if a[i] < b[i] { a[i] } else { b[i] })
    }
    #[inline(always)]
    fn max(a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| if a[i] > b[i] { a[i] } else { b[i] })
    }
    #[inline(always)]
    fn lt(a: Self::V, b: Self::V) -> Self::M {
        std::array::from_fn(|i| a[i] < b[i])
    }
    #[inline(always)]
    fn le(a: Self::V, b: Self::V) -> Self::M {
        std::array::from_fn(|i| a[i] <= b[i])
    }
    #[inline(always)]
    fn gt(a: Self::V, b: Self::V) -> Self::M {
        std::array::from_fn(|i| a[i] > b[i])
    }
    #[inline(always)]
    fn eq(a: Self::V, b: Self::V) -> Self::M {
        std::array::from_fn(|i| a[i] == b[i])
    }
    #[inline(always)]
    fn and(a: Self::M, b: Self::M) -> Self::M {
        std::array::from_fn(|i| a[i] & b[i])
    }
    #[inline(always)]
    fn or(a: Self::M, b: Self::M) -> Self::M {
        std::array::from_fn(|i| a[i] | b[i])
    }
    #[inline(always)]
    fn andnot(a: Self::M, b: Self::M) -> Self::M {
        std::array::from_fn(|i| !a[i] & b[i])
    }
    #[inline(always)]
    fn select(m: Self::M, a: Self::V, b: Self::V) -> Self::V {
        std::array::from_fn(|i| if m[i] { a[i] } else { b[i] })
    }
    #[inline(always)]
    fn bits(m: Self::M) -> u32 {
        m.iter()
            .enumerate()
            .fold(0, |acc, (i, &b)| acc | (u32::from(b) << i))
    }
    #[inline(always)]
    fn mask(bits: u32) -> Self::M {
        std::array::from_fn(|i| bits & (1 << i) != 0)
    }
    #[inline(always)]
    fn columns8(rows: &[&[f32; 8]]) -> [Self::V; 8] {
        std::array::from_fn(|j| std::array::from_fn(|i| rows[i][j]))
    }
}

/// The mask of the first `n` lanes (all when `n >= W`).
#[inline(always)]
pub(crate) fn lanes_below<L: Lanes>(n: usize) -> u32 {
    if n >= L::W {
        (1u32 << L::W) - 1
    } else {
        (1u32 << n) - 1
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use x86::{Avx2, Avx512, Sse41, prefetch};

/// Asks the CPU to start loading the cache lines of `value` (a no-op off x86-64): the
/// traversals prefetch the children they will visit next, so that their loads overlap.
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
pub(crate) fn prefetch<T>(_value: &T) {}

#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod x86 {
    use super::Lanes;
    use std::arch::x86_64::*;

    /// Wraps an intrinsic call.
    ///
    /// SAFETY (for every use in this module): the intrinsics are `unsafe` only because they
    /// need their instruction set. [`Sse41`] and [`Avx2`] are used exclusively by the
    /// kernels instantiated inside `#[target_feature(enable = "sse4.1")]` and
    /// `#[target_feature(enable = "avx2")]` functions, which `crate::Isa::detect` lets run
    /// only after `is_x86_feature_detected!` confirmed the feature. Loads and stores go
    /// through slices of at least `W` elements (indexed first, so a short slice panics
    /// before any pointer is used), and the unaligned variants need no alignment.
    macro_rules! intrinsic {
        ($e:expr) => {
            unsafe { $e }
        };
    }

    /// Asks the CPU to start loading the cache lines of `value` into every cache level.
    #[inline(always)]
    pub(crate) fn prefetch<T>(value: &T) {
        let p = std::ptr::from_ref(value).cast::<i8>();
        let lines = std::mem::size_of::<T>().div_ceil(64);
        for line in 0..lines {
            // SAFETY: a prefetch is a hint: it never faults and changes no memory, and
            // SSE (which has it) is part of the x86-64 baseline. The address stays inside
            // (or one line past the start of the last line of) `value`.
            intrinsic!(_mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(64 * line)));
        }
    }

    /// SSE4.1: four lanes in `__m128`.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Sse41;

    impl Lanes for Sse41 {
        const W: usize = 4;
        type Single = Self;
        type Narrow = Self;
        type V = __m128;
        type M = __m128;

        #[inline(always)]
        fn splat(x: f32) -> Self::V {
            intrinsic!(_mm_set1_ps(x))
        }
        #[inline(always)]
        fn load(s: &[f32]) -> Self::V {
            let s = &s[..4];
            intrinsic!(_mm_loadu_ps(s.as_ptr()))
        }
        #[inline(always)]
        fn store(v: Self::V, out: &mut [f32]) {
            let out = &mut out[..4];
            intrinsic!(_mm_storeu_ps(out.as_mut_ptr(), v));
        }
        #[inline(always)]
        fn add(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_add_ps(a, b))
        }
        #[inline(always)]
        fn sub(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_sub_ps(a, b))
        }
        #[inline(always)]
        fn mul(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_mul_ps(a, b))
        }
        #[inline(always)]
        fn div(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_div_ps(a, b))
        }
        #[inline(always)]
        fn min(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_min_ps(a, b))
        }
        #[inline(always)]
        fn max(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_max_ps(a, b))
        }
        #[inline(always)]
        fn lt(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm_cmplt_ps(a, b))
        }
        #[inline(always)]
        fn le(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm_cmple_ps(a, b))
        }
        #[inline(always)]
        fn gt(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm_cmpgt_ps(a, b))
        }
        #[inline(always)]
        fn eq(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm_cmpeq_ps(a, b))
        }
        #[inline(always)]
        fn and(a: Self::M, b: Self::M) -> Self::M {
            intrinsic!(_mm_and_ps(a, b))
        }
        #[inline(always)]
        fn or(a: Self::M, b: Self::M) -> Self::M {
            intrinsic!(_mm_or_ps(a, b))
        }
        #[inline(always)]
        fn andnot(a: Self::M, b: Self::M) -> Self::M {
            intrinsic!(_mm_andnot_ps(a, b))
        }
        #[inline(always)]
        fn select(m: Self::M, a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm_blendv_ps(b, a, m))
        }
        #[inline(always)]
        fn bits(m: Self::M) -> u32 {
            intrinsic!(_mm_movemask_ps(m)) as u32
        }
        #[inline(always)]
        fn mask(bits: u32) -> Self::M {
            let lanes = intrinsic!(_mm_set_epi32(8, 4, 2, 1));
            let b = intrinsic!(_mm_set1_epi32(bits as i32));
            let m = intrinsic!(_mm_cmpeq_epi32(_mm_and_si128(b, lanes), lanes));
            intrinsic!(_mm_castsi128_ps(m))
        }
        #[inline(always)]
        fn columns8(rows: &[&[f32; 8]]) -> [Self::V; 8] {
            let rows = &rows[..4];
            let mut out = [Self::splat(0.0); 8];
            for half in 0..2 {
                let r0 = Self::load(&rows[0][4 * half..]);
                let r1 = Self::load(&rows[1][4 * half..]);
                let r2 = Self::load(&rows[2][4 * half..]);
                let r3 = Self::load(&rows[3][4 * half..]);
                // (r0[0] r1[0] r0[1] r1[1]), (r2[0] r3[0] r2[1] r3[1]), and the same of 2, 3.
                let t0 = intrinsic!(_mm_unpacklo_ps(r0, r1));
                let t1 = intrinsic!(_mm_unpacklo_ps(r2, r3));
                let t2 = intrinsic!(_mm_unpackhi_ps(r0, r1));
                let t3 = intrinsic!(_mm_unpackhi_ps(r2, r3));
                out[4 * half] = intrinsic!(_mm_movelh_ps(t0, t1));
                out[4 * half + 1] = intrinsic!(_mm_movehl_ps(t1, t0));
                out[4 * half + 2] = intrinsic!(_mm_movelh_ps(t2, t3));
                out[4 * half + 3] = intrinsic!(_mm_movehl_ps(t3, t2));
            }
            out
        }
    }

    /// AVX2: eight lanes in `__m256`.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx2;

    impl Lanes for Avx2 {
        const W: usize = 8;
        type Single = Self;
        type Narrow = Sse41;
        type V = __m256;
        type M = __m256;

        #[inline(always)]
        fn splat(x: f32) -> Self::V {
            intrinsic!(_mm256_set1_ps(x))
        }
        #[inline(always)]
        fn load(s: &[f32]) -> Self::V {
            let s = &s[..8];
            intrinsic!(_mm256_loadu_ps(s.as_ptr()))
        }
        #[inline(always)]
        fn store(v: Self::V, out: &mut [f32]) {
            let out = &mut out[..8];
            intrinsic!(_mm256_storeu_ps(out.as_mut_ptr(), v));
        }
        #[inline(always)]
        fn add(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_add_ps(a, b))
        }
        #[inline(always)]
        fn sub(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_sub_ps(a, b))
        }
        #[inline(always)]
        fn mul(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_mul_ps(a, b))
        }
        #[inline(always)]
        fn div(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_div_ps(a, b))
        }
        #[inline(always)]
        fn min(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_min_ps(a, b))
        }
        #[inline(always)]
        fn max(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_max_ps(a, b))
        }
        #[inline(always)]
        fn lt(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm256_cmp_ps::<_CMP_LT_OQ>(a, b))
        }
        #[inline(always)]
        fn le(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm256_cmp_ps::<_CMP_LE_OQ>(a, b))
        }
        #[inline(always)]
        fn gt(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm256_cmp_ps::<_CMP_GT_OQ>(a, b))
        }
        #[inline(always)]
        fn eq(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm256_cmp_ps::<_CMP_EQ_OQ>(a, b))
        }
        #[inline(always)]
        fn and(a: Self::M, b: Self::M) -> Self::M {
            intrinsic!(_mm256_and_ps(a, b))
        }
        #[inline(always)]
        fn or(a: Self::M, b: Self::M) -> Self::M {
            intrinsic!(_mm256_or_ps(a, b))
        }
        #[inline(always)]
        fn andnot(a: Self::M, b: Self::M) -> Self::M {
            intrinsic!(_mm256_andnot_ps(a, b))
        }
        #[inline(always)]
        fn select(m: Self::M, a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm256_blendv_ps(b, a, m))
        }
        #[inline(always)]
        fn bits(m: Self::M) -> u32 {
            intrinsic!(_mm256_movemask_ps(m)) as u32
        }
        #[inline(always)]
        fn mask(bits: u32) -> Self::M {
            let lanes = intrinsic!(_mm256_set_epi32(128, 64, 32, 16, 8, 4, 2, 1));
            let b = intrinsic!(_mm256_set1_epi32(bits as i32));
            let m = intrinsic!(_mm256_cmpeq_epi32(_mm256_and_si256(b, lanes), lanes));
            intrinsic!(_mm256_castsi256_ps(m))
        }
        #[inline(always)]
        fn columns8(rows: &[&[f32; 8]]) -> [Self::V; 8] {
            let rows = &rows[..8];
            let r: [__m256; 8] = [
                Self::load(rows[0]),
                Self::load(rows[1]),
                Self::load(rows[2]),
                Self::load(rows[3]),
                Self::load(rows[4]),
                Self::load(rows[5]),
                Self::load(rows[6]),
                Self::load(rows[7]),
            ];
            // Pairs of rows interleaved: (a[0] b[0] a[1] b[1] | a[4] b[4] a[5] b[5]) and
            // (a[2] b[2] a[3] b[3] | a[6] b[6] a[7] b[7]).
            let t0 = intrinsic!(_mm256_unpacklo_ps(r[0], r[1]));
            let t1 = intrinsic!(_mm256_unpackhi_ps(r[0], r[1]));
            let t2 = intrinsic!(_mm256_unpacklo_ps(r[2], r[3]));
            let t3 = intrinsic!(_mm256_unpackhi_ps(r[2], r[3]));
            let t4 = intrinsic!(_mm256_unpacklo_ps(r[4], r[5]));
            let t5 = intrinsic!(_mm256_unpackhi_ps(r[4], r[5]));
            let t6 = intrinsic!(_mm256_unpacklo_ps(r[6], r[7]));
            let t7 = intrinsic!(_mm256_unpackhi_ps(r[6], r[7]));
            // Columns j and j + 4 of four rows: u0 holds 0 | 4, u1 1 | 5, u2 2 | 6, u3 3 | 7.
            let u0 = intrinsic!(_mm256_shuffle_ps::<0x44>(t0, t2));
            let u1 = intrinsic!(_mm256_shuffle_ps::<0xEE>(t0, t2));
            let u2 = intrinsic!(_mm256_shuffle_ps::<0x44>(t1, t3));
            let u3 = intrinsic!(_mm256_shuffle_ps::<0xEE>(t1, t3));
            let u4 = intrinsic!(_mm256_shuffle_ps::<0x44>(t4, t6));
            let u5 = intrinsic!(_mm256_shuffle_ps::<0xEE>(t4, t6));
            let u6 = intrinsic!(_mm256_shuffle_ps::<0x44>(t5, t7));
            let u7 = intrinsic!(_mm256_shuffle_ps::<0xEE>(t5, t7));
            [
                intrinsic!(_mm256_permute2f128_ps::<0x20>(u0, u4)),
                intrinsic!(_mm256_permute2f128_ps::<0x20>(u1, u5)),
                intrinsic!(_mm256_permute2f128_ps::<0x20>(u2, u6)),
                intrinsic!(_mm256_permute2f128_ps::<0x20>(u3, u7)),
                intrinsic!(_mm256_permute2f128_ps::<0x31>(u0, u4)),
                intrinsic!(_mm256_permute2f128_ps::<0x31>(u1, u5)),
                intrinsic!(_mm256_permute2f128_ps::<0x31>(u2, u6)),
                intrinsic!(_mm256_permute2f128_ps::<0x31>(u3, u7)),
            ]
        }
    }

    /// AVX-512F: sixteen lanes in `__m512`, masks in `__mmask16` (a measured extra: its
    /// single-ray code is AVX2's, since BVH8 nodes hold eight children).
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx512;

    impl Lanes for Avx512 {
        const W: usize = 16;
        type Single = Avx2;
        type Narrow = Sse41;
        type V = __m512;
        type M = __mmask16;

        #[inline(always)]
        fn splat(x: f32) -> Self::V {
            intrinsic!(_mm512_set1_ps(x))
        }
        #[inline(always)]
        fn load(s: &[f32]) -> Self::V {
            let s = &s[..16];
            intrinsic!(_mm512_loadu_ps(s.as_ptr()))
        }
        #[inline(always)]
        fn store(v: Self::V, out: &mut [f32]) {
            let out = &mut out[..16];
            intrinsic!(_mm512_storeu_ps(out.as_mut_ptr(), v));
        }
        #[inline(always)]
        fn add(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_add_ps(a, b))
        }
        #[inline(always)]
        fn sub(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_sub_ps(a, b))
        }
        #[inline(always)]
        fn mul(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_mul_ps(a, b))
        }
        #[inline(always)]
        fn div(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_div_ps(a, b))
        }
        #[inline(always)]
        fn min(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_min_ps(a, b))
        }
        #[inline(always)]
        fn max(a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_max_ps(a, b))
        }
        #[inline(always)]
        fn lt(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm512_cmp_ps_mask::<_CMP_LT_OQ>(a, b))
        }
        #[inline(always)]
        fn le(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm512_cmp_ps_mask::<_CMP_LE_OQ>(a, b))
        }
        #[inline(always)]
        fn gt(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm512_cmp_ps_mask::<_CMP_GT_OQ>(a, b))
        }
        #[inline(always)]
        fn eq(a: Self::V, b: Self::V) -> Self::M {
            intrinsic!(_mm512_cmp_ps_mask::<_CMP_EQ_OQ>(a, b))
        }
        #[inline(always)]
        fn and(a: Self::M, b: Self::M) -> Self::M {
            a & b
        }
        #[inline(always)]
        fn or(a: Self::M, b: Self::M) -> Self::M {
            a | b
        }
        #[inline(always)]
        fn andnot(a: Self::M, b: Self::M) -> Self::M {
            !a & b
        }
        #[inline(always)]
        fn select(m: Self::M, a: Self::V, b: Self::V) -> Self::V {
            intrinsic!(_mm512_mask_blend_ps(m, b, a))
        }
        #[inline(always)]
        fn bits(m: Self::M) -> u32 {
            u32::from(m)
        }
        #[inline(always)]
        fn mask(bits: u32) -> Self::M {
            bits as u16
        }
        #[inline(always)]
        fn columns8(rows: &[&[f32; 8]]) -> [Self::V; 8] {
            let (lo, hi) = (Avx2::columns8(&rows[..8]), Avx2::columns8(&rows[8..16]));
            let mut out = [Self::splat(0.0); 8];
            for (o, (lo, hi)) in out.iter_mut().zip(lo.into_iter().zip(hi)) {
                let wide = intrinsic!(_mm512_castpd256_pd512(_mm256_castps_pd(lo)));
                let both = intrinsic!(_mm512_insertf64x4::<1>(wide, _mm256_castps_pd(hi)));
                *o = intrinsic!(_mm512_castpd_ps(both));
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each instruction set agrees with the portable lanes, including on NaN operands.
    fn agrees<L: Lanes>() {
        let a: Vec<f32> = (0..16)
            .map(|i| [1.0, -2.0, f32::NAN, 0.0][i % 4] * (i as f32 + 1.0))
            .collect();
        let b: Vec<f32> = (0..16)
            .map(|i| [0.5, -3.0, 1.0, f32::NAN][(i / 2) % 4])
            .collect();
        let (x, y) = (L::load(&a), L::load(&b));
        let mut out = vec![0.0f32; L::W];
        let check = |v: L::V, f: &dyn Fn(f32, f32) -> f32, what: &str| {
            let mut o = vec![0.0f32; L::W];
            L::store(v, &mut o);
            for i in 0..L::W {
                let want = f(a[i], b[i]);
                assert!(
                    o[i].to_bits() == want.to_bits() || (o[i].is_nan() && want.is_nan()),
                    "{} {what} lane {i}: {} vs {want}",
                    std::any::type_name::<L>(),
                    o[i]
                );
            }
        };
        check(L::add(x, y), &|p, q| p + q, "add");
        check(L::sub(x, y), &|p, q| p - q, "sub");
        check(L::mul(x, y), &|p, q| p * q, "mul");
        check(L::div(x, y), &|p, q| p / q, "div");
        check(L::min(x, y), &|p, q| if p < q { p } else { q }, "min");
        check(L::max(x, y), &|p, q| if p > q { p } else { q }, "max");
        let lt = L::bits(L::lt(x, y));
        let le = L::bits(L::le(x, y));
        let gt = L::bits(L::gt(x, y));
        let eq = L::bits(L::eq(x, y));
        for i in 0..L::W {
            assert_eq!(lt >> i & 1 == 1, a[i] < b[i]);
            assert_eq!(le >> i & 1 == 1, a[i] <= b[i]);
            assert_eq!(gt >> i & 1 == 1, a[i] > b[i]);
            assert_eq!(eq >> i & 1 == 1, a[i] == b[i]);
        }
        for bits in [0u32, 1, 0b1010, (1 << L::W) - 1] {
            assert_eq!(L::bits(L::mask(bits)), bits);
            L::store(L::select(L::mask(bits), x, y), &mut out);
            for i in 0..L::W {
                let want = if bits >> i & 1 == 1 { a[i] } else { b[i] };
                assert!(out[i].to_bits() == want.to_bits());
            }
        }
        assert_eq!(L::bits(L::andnot(L::mask(0b11), L::mask(0b110))), 0b100);
        assert_eq!(L::bits(L::or(L::mask(0b1), L::mask(0b10))), 0b11);
        assert_eq!(L::bits(L::and(L::mask(0b11), L::mask(0b10))), 0b10);
        // Transposes: row i, column j holds 100 i + j (a NaN in one place, kept as is).
        let rows: Vec<[f32; 8]> = (0..16)
            .map(|i| {
                std::array::from_fn(|j| {
                    if i == 3 && j == 5 {
                        f32::NAN
                    } else {
                        (100 * i + j) as f32
                    }
                })
            })
            .collect();
        let refs: Vec<&[f32; 8]> = rows.iter().collect();
        for (j, column) in L::columns8(&refs).into_iter().enumerate() {
            L::store(column, &mut out);
            for (i, row) in rows.iter().take(L::W).enumerate() {
                assert_eq!(out[i].to_bits(), row[j].to_bits(), "column {j} row {i}");
            }
        }
    }

    /// The rows of a packet's rays are their fields, in the documented order, and lanes
    /// past the last ray repeat it.
    #[test]
    fn ray_rows_hold_the_fields() {
        use raybench_geometry::Vec3;
        let rays = [
            Ray::with_interval(
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::new(0.5, -4.0, 2.0),
                0.25,
                9.0,
            ),
            Ray::with_interval(
                Vec3::new(-1.0, 0.0, 7.0),
                Vec3::new(-2.0, 1.0, 8.0),
                0.0,
                3.0,
            ),
        ];
        let (head, tail) = ray_rows::<Portable>(&rays);
        for (lane, r) in [&rays[0], &rays[1], &rays[1], &rays[1]]
            .into_iter()
            .enumerate()
        {
            let mut want = [0.0; 14];
            want[..3].copy_from_slice(&r.origin.to_array());
            want[3..6].copy_from_slice(&r.dir.to_array());
            want[6..9].copy_from_slice(&r.inv_dir.to_array());
            (want[9], want[10]) = (r.t_min, r.t_max);
            want[11..].copy_from_slice(&r.shear.to_array());
            assert_eq!(head[lane][..], want[..8], "lane {lane}");
            assert_eq!(tail[lane][..], want[6..], "lane {lane}");
        }
    }

    #[test]
    fn portable_lanes() {
        agrees::<Portable>();
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sse41_lanes() {
        if is_x86_feature_detected!("sse4.1") {
            agrees::<Sse41>();
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_lanes() {
        if is_x86_feature_detected!("avx512f") {
            agrees::<Avx512>();
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_lanes() {
        if is_x86_feature_detected!("avx2") {
            agrees::<Avx2>();
        }
    }
}
