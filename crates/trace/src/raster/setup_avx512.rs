//! [`Setup::new`] of eight triangles at once, in AVX-512 f64 lanes.
//!
//! The setup of a mesh's triangle is a chain of f64 divisions and a square
//! root whose latencies, one triangle after the other, dominated the
//! rasterizer's setup. Here every lane does the operations of the scalar
//! setup, in its order and with its roundings (a product and a sum are never
//! fused; a division stays a division), so a lane's setup is the scalar
//! one bit for bit. Only the common case is taken: a vouched triangle wholly
//! beyond its cut depth, whose box meets the region, with finite numbers
//! throughout. Every other lane (clipped, edge-on, near the eye's plane,
//! hidden, non-finite) is left to the scalar setup, which alone knows the
//! other branches; where `min` and `max` would treat NaN differently, their
//! operands are finite by then.

use std::arch::x86_64::*;
use std::mem::{MaybeUninit, offset_of, size_of};

use glam::DVec3;

use super::{BIN, DEPTH, EDGE_F32, EDGE_F64, EDGE_ON, Kind, SAFE_DEPTH, Seen, Setup, View};
use crate::scene::Region;

/// Triangles set up together: the f64 lanes of a vector.
const WIDTH: usize = super::SETUP_LANES;
const _: () = assert!(WIDTH * size_of::<f64>() == size_of::<__m512d>());

/// The setups of the triangles `triangles` (at most [`WIDTH`], indices
/// into `seen`) into `out`, one per triangle: a lane whose setup the vector
/// path takes is written, and `true` in the returned mask; the others are
/// left for the scalar setup.
///
/// # Safety
/// The CPU must have AVX-512F and AVX2.
#[target_feature(enable = "avx512f,avx2")]
pub(super) unsafe fn set_up(
    view: &View,
    seen: &[Seen],
    triangles: &[[u32; 3]],
    z_ref: f64,
    region: &Region,
    out: &mut [MaybeUninit<Setup>],
) -> u8 {
    debug_assert!(triangles.len() <= WIDTH && out.len() == triangles.len());
    // Byte offsets of the vertices' `Seen`, checked in bounds (a lane past
    // the end repeats the last triangle).
    let mut offsets = [[0i64; WIDTH]; 3];
    let Some(&last) = triangles.last() else {
        return 0;
    };
    for l in 0..WIDTH {
        let triangle = triangles.get(l).copied().unwrap_or(last);
        for (v, &i) in triangle.iter().enumerate() {
            if i as usize >= seen.len() {
                // The scalar setup reports the bad index.
                return 0;
            }
            offsets[v][l] = i as i64 * size_of::<Seen>() as i64;
        }
    }
    let base = seen.as_ptr().cast::<u8>();
    // (Written out, as below: the compiler left `map`'s closures as calls.)
    // SAFETY: every offset is that of a `Seen` of `seen`, checked above.
    let p = unsafe {
        [
            SeenLanes::gather(base, &offsets[0]),
            SeenLanes::gather(base, &offsets[1]),
            SeenLanes::gather(base, &offsets[2]),
        ]
    };
    let lanes = lanes(view, p, z_ref, region);
    let mut written = 0u8;
    for (l, slot) in out.iter_mut().enumerate() {
        if lanes.taken >> l & 1 == 1 {
            slot.write(lanes.setup(l));
            written |= 1 << l;
        }
    }
    written
}

/// A vertex's [`Seen`] in each of eight lanes.
#[derive(Clone, Copy)]
struct SeenLanes {
    offset: [__m512d; 3],
    length: __m512d,
    depth: __m512d,
    x: __m512d,
    y: __m512d,
}

impl SeenLanes {
    /// The `Seen` at each byte offset of `offsets` from `base`.
    ///
    /// # Safety
    /// Each offset must be that of a `Seen` from `base`.
    #[inline]
    #[target_feature(enable = "avx512f,avx2")]
    unsafe fn gather(base: *const u8, offsets: &[i64; WIDTH]) -> Self {
        // SAFETY: the caller's offsets are those of `Seen`s, and the fields
        // are f64 at their own offsets within.
        unsafe {
            let index = _mm512_loadu_si512(offsets.as_ptr().cast());
            let field = |at: usize| _mm512_i64gather_pd::<1>(index, base.add(at).cast());
            let offset = offset_of!(Seen, offset);
            Self {
                offset: [
                    field(offset + offset_of!(DVec3, x)),
                    field(offset + offset_of!(DVec3, y)),
                    field(offset + offset_of!(DVec3, z)),
                ],
                length: field(offset_of!(Seen, length)),
                depth: field(offset_of!(Seen, depth)),
                x: field(offset_of!(Seen, x)),
                y: field(offset_of!(Seen, y)),
            }
        }
    }
}

/// The lanes' setups, field by field, and the lanes taken.
struct Lanes {
    a: [[f32; WIDTH]; 3],
    b: [[f32; WIDTH]; 3],
    c: [[f32; WIDTH]; 3],
    m: [[f32; WIDTH]; 3],
    sum_margin: [f32; WIDTH],
    inv_d: [f32; WIDTH],
    near: [f32; WIDTH],
    ccw: u8,
    x0: [u32; WIDTH],
    y0: [u32; WIDTH],
    x1: [u32; WIDTH],
    y1: [u32; WIDTH],
    taken: u8,
}

impl Lanes {
    #[inline(always)]
    fn setup(&self, l: usize) -> Setup {
        Setup {
            a: [self.a[0][l], self.a[1][l], self.a[2][l]],
            b: [self.b[0][l], self.b[1][l], self.b[2][l]],
            c: [self.c[0][l], self.c[1][l], self.c[2][l]],
            m: [self.m[0][l], self.m[1][l], self.m[2][l]],
            sum_margin: self.sum_margin[l],
            inv_d: self.inv_d[l],
            near: self.near[l],
            ccw: self.ccw >> l & 1 == 1,
            x0: self.x0[l],
            y0: self.y0[l],
            x1: self.x1[l],
            y1: self.y1[l],
            kind: Kind::Vouched,
        }
    }
}

// Each helper is one IEEE operation per lane, as the scalar code writes it.

#[inline]
#[target_feature(enable = "avx512f")]
fn splat(x: f64) -> __m512d {
    _mm512_set1_pd(x)
}

#[inline]
#[target_feature(enable = "avx512f")]
fn add(a: __m512d, b: __m512d) -> __m512d {
    _mm512_add_pd(a, b)
}

#[inline]
#[target_feature(enable = "avx512f")]
fn sub(a: __m512d, b: __m512d) -> __m512d {
    _mm512_sub_pd(a, b)
}

#[inline]
#[target_feature(enable = "avx512f")]
fn mul(a: __m512d, b: __m512d) -> __m512d {
    _mm512_mul_pd(a, b)
}

#[inline]
#[target_feature(enable = "avx512f")]
fn div(a: __m512d, b: __m512d) -> __m512d {
    _mm512_div_pd(a, b)
}

#[inline]
#[target_feature(enable = "avx512f")]
fn abs(a: __m512d) -> __m512d {
    _mm512_abs_pd(a)
}

/// `f64::max` of operands that are not NaN.
#[inline]
#[target_feature(enable = "avx512f")]
fn max(a: __m512d, b: __m512d) -> __m512d {
    _mm512_max_pd(a, b)
}

/// `f64::min` of operands that are not NaN.
#[inline]
#[target_feature(enable = "avx512f")]
fn min(a: __m512d, b: __m512d) -> __m512d {
    _mm512_min_pd(a, b)
}

/// `DVec3::dot`: `(x·x') + (y·y') + (z·z')`.
#[inline]
#[target_feature(enable = "avx512f")]
fn dot(p: [__m512d; 3], q: [__m512d; 3]) -> __m512d {
    add(add(mul(p[0], q[0]), mul(p[1], q[1])), mul(p[2], q[2]))
}

/// `DVec3::cross`.
#[inline]
#[target_feature(enable = "avx512f")]
fn cross(p: [__m512d; 3], q: [__m512d; 3]) -> [__m512d; 3] {
    [
        sub(mul(p[1], q[2]), mul(q[1], p[2])),
        sub(mul(p[2], q[0]), mul(q[2], p[0])),
        sub(mul(p[0], q[1]), mul(q[0], p[1])),
    ]
}

#[inline]
#[target_feature(enable = "avx512f")]
fn sub3(p: [__m512d; 3], q: [__m512d; 3]) -> [__m512d; 3] {
    [sub(p[0], q[0]), sub(p[1], q[1]), sub(p[2], q[2])]
}

/// The lanes that are finite.
#[inline]
#[target_feature(enable = "avx512f")]
fn finite(a: __m512d) -> __mmask8 {
    _mm512_cmp_pd_mask::<_CMP_LT_OQ>(abs(a), splat(f64::INFINITY))
}

#[inline]
#[target_feature(enable = "avx512f")]
fn gt(a: __m512d, b: __m512d) -> __mmask8 {
    _mm512_cmp_pd_mask::<_CMP_GT_OQ>(a, b)
}

#[inline]
#[target_feature(enable = "avx512f")]
fn ge(a: __m512d, b: __m512d) -> __mmask8 {
    _mm512_cmp_pd_mask::<_CMP_GE_OQ>(a, b)
}

/// `x as f32` (rounded to nearest, as `as` rounds).
#[inline]
#[target_feature(enable = "avx512f")]
fn to_f32(a: __m512d) -> __m256 {
    _mm512_cvtpd_ps(a)
}

#[inline]
#[target_feature(enable = "avx512f,avx2")]
fn store_f32(a: __m256) -> [f32; WIDTH] {
    let mut out = [0.0; WIDTH];
    // SAFETY: `out` holds eight f32.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), a) };
    out
}

/// The scalar setup's `up`: `x` rounded to the nearest f32, then to the
/// next one above when that is below `x` (`f32::next_up`, for the values
/// other than −0 and NaN that it meets: one step of the bits away from
/// zero for a positive value, towards it for a negative one).
#[inline]
#[target_feature(enable = "avx512f,avx2")]
fn up(x: __m512d) -> __m256 {
    let y = to_f32(x);
    let below = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(_mm512_cvtps_pd(y), x);
    let bits = _mm256_castps_si256(y);
    let negative = _mm256_srai_epi32::<31>(bits);
    // +1 where positive, −1 where negative.
    let step = _mm256_or_si256(negative, _mm256_set1_epi32(1));
    let stepped = _mm256_add_epi32(bits, step);
    let below = wide_mask(below);
    _mm256_castsi256_ps(_mm256_blendv_epi8(bits, stepped, below))
}

/// The lanes of `mask` as all-ones 32-bit lanes (AVX-512F alone has no
/// 256-bit mask move).
#[inline]
#[target_feature(enable = "avx512f,avx2")]
fn wide_mask(mask: __mmask8) -> __m256i {
    let lanes = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    let m = _mm256_set1_epi32(i32::from(mask));
    _mm256_cmpeq_epi32(_mm256_and_si256(m, lanes), lanes)
}

/// `View::screen_box`'s clamp of `v` to `[lo, hi]` and truncation, the
/// integer also back in f64.
#[inline]
#[target_feature(enable = "avx512f,avx2")]
fn clamp(v: __m512d, lo: u32, hi: u32) -> (__m256i, __m512d) {
    let clamped = min(max(v, splat(f64::from(lo))), splat(f64::from(hi)));
    let integer = _mm512_cvttpd_epu32(clamped);
    (integer, _mm512_cvtepu32_pd(integer))
}

#[inline]
#[target_feature(enable = "avx512f,avx2")]
fn store_u32(x: __m256i) -> [u32; WIDTH] {
    let mut out = [0u32; WIDTH];
    // SAFETY: `out` holds eight u32.
    unsafe { _mm256_storeu_si256(out.as_mut_ptr().cast(), x) };
    out
}

#[inline]
#[target_feature(enable = "avx512f")]
fn splat3(q: DVec3) -> [__m512d; 3] {
    [splat(q.x), splat(q.y), splat(q.z)]
}

/// `-x`: its sign flipped.
#[inline]
#[target_feature(enable = "avx512f")]
fn negate(x: __m512d) -> __m512d {
    _mm512_castsi512_pd(_mm512_xor_si512(
        _mm512_castpd_si512(x),
        _mm512_set1_epi64(i64::MIN),
    ))
}

/// `EdgeTerms::coefficients` of the edge normal `e`, times `orientation`,
/// with the camera's `[u, v, w]` as `frame`, from the pixel `corner`.
#[inline]
#[target_feature(enable = "avx512f")]
fn edge(
    e: [__m512d; 3],
    orientation: __m512d,
    [u, v, w]: [[__m512d; 3]; 3],
    view: &View,
    (ox, oy): (__m512d, __m512d),
) -> [__m512d; 3] {
    let g = [
        mul(e[0], orientation),
        mul(e[1], orientation),
        mul(e[2], orientation),
    ];
    let (gu, gv, gw) = (dot(g, u), dot(g, v), dot(g, w));
    let ca = mul(gu, splat(view.step_x));
    let cb = mul(negate(gv), splat(view.step_y));
    let cc = add(add(add(sub(gw, gu), gv), mul(ca, ox)), mul(cb, oy));
    [ca, cb, cc]
}

/// `Setup::new`'s largest term of the edge `[ca, cb, cc]` over the box,
/// whose extents plus a bin are `reach`.
#[inline]
#[target_feature(enable = "avx512f")]
fn largest([ca, cb, cc]: [__m512d; 3], (reach_x, reach_y): (__m512d, __m512d)) -> __m512d {
    add(add(mul(abs(ca), reach_x), mul(abs(cb), reach_y)), abs(cc))
}

/// The setups of the eight triangles `p`, and the lanes whose setup is
/// the scalar one's common case (see the module's paragraph).
#[inline]
#[target_feature(enable = "avx512f,avx2")]
fn lanes(view: &View, p: [SeenLanes; 3], z_ref: f64, region: &Region) -> Lanes {
    let [a, b, c] = [p[0].offset, p[1].offset, p[2].offset];
    let lengths = [p[0].length, p[1].length, p[2].length];
    let depth = [p[0].depth, p[1].depth, p[2].depth];
    // Every input finite: then `min` and `max` are those of the scalar code.
    let mut taken = 0xff;
    for q in &p {
        for v in [
            q.offset[0],
            q.offset[1],
            q.offset[2],
            q.length,
            q.depth,
            q.x,
            q.y,
        ] {
            taken &= finite(v);
        }
    }
    // `EdgeTerms::new`.
    let e = [cross(b, c), cross(c, a), cross(a, b)];
    let d = dot(a, e[0]);
    let size = max(max(lengths[0], lengths[1]), lengths[2]);
    let z_min = min(min(depth[0], depth[1]), depth[2]);
    let n = cross(sub3(b, a), sub3(c, a));
    let normal = _mm512_sqrt_pd(dot(n, n));
    let d_abs = abs(d);
    // Not edge-on, and vouched.
    taken &= gt(d_abs, mul(mul(splat(EDGE_ON), size), normal));
    taken &= gt(z_min, mul(splat(SAFE_DEPTH), size));
    let z_cut = mul(div(div(d_abs, normal), splat(view.reach)), splat(0.5));
    taken &= gt(z_cut, splat(0.0)) & finite(z_cut);
    // Wholly at depth `z_cut` or more: the box is that of the vertices.
    for z in depth {
        taken &= ge(z, z_cut);
    }
    let x_min = min(min(p[0].x, p[1].x), p[2].x);
    let x_max = max(max(p[0].x, p[1].x), p[2].x);
    let y_min = min(min(p[0].y, p[1].y), p[2].y);
    let y_max = max(max(p[0].y, p[1].y), p[2].y);
    let whole = super::whole(region);
    // `View::screen_box`'s clamp, the integer back in f64.
    let (x0, ox) = clamp(sub(x_min, splat(1.0)), region.x, whole.x1);
    let (x1, x1f) = clamp(add(x_max, splat(2.0)), region.x, whole.x1);
    let (y0, oy) = clamp(sub(y_min, splat(1.0)), region.y, whole.y1);
    let (y1, y1f) = clamp(add(y_max, splat(2.0)), region.y, whole.y1);
    taken &= gt(x1f, ox) & gt(y1f, oy);
    // `EdgeTerms::coefficients`, from the box's corner.
    let ccw = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(d, splat(0.0));
    let orientation = _mm512_mask_blend_pd(ccw, splat(1.0), splat(-1.0));
    let (u, v, w) = (view.u, view.v, view.w);
    let frame = [splat3(u), splat3(v), splat3(w)];
    let corner = (ox, oy);
    let coefficients = [
        edge(e[0], orientation, frame, view, corner),
        edge(e[1], orientation, frame, view, corner),
        edge(e[2], orientation, frame, view, corner),
    ];
    let bin = splat(f64::from(BIN));
    let reach = (add(sub(x1f, ox), bin), add(sub(y1f, oy), bin));
    let largest = [
        largest(coefficients[0], reach),
        largest(coefficients[1], reach),
        largest(coefficients[2], reach),
    ];
    // `EdgeTerms::margins`.
    let m_scale = splat(EDGE_F64 * view.reach);
    let m64 = [
        mul(mul(m_scale, lengths[1]), lengths[2]),
        mul(mul(m_scale, lengths[2]), lengths[0]),
        mul(mul(m_scale, lengths[0]), lengths[1]),
    ];
    for i in 0..3 {
        taken &= finite(largest[i]) & finite(m64[i]);
    }
    let scale = max(max(largest[0], largest[1]), largest[2]);
    taken &= gt(scale, splat(0.0));
    let k = div(splat(1.0), scale);
    let margin = |i: usize| mul(add(mul(splat(EDGE_F32), largest[i]), m64[i]), k);
    let m = [margin(0), margin(1), margin(2)];
    let sum_margin = add(
        add(add(m[0], m[1]), m[2]),
        mul(
            mul(splat(DEPTH), add(add(largest[0], largest[1]), largest[2])),
            k,
        ),
    );
    let inv_d = div(splat(z_ref), mul(d_abs, k));
    let inv_d32 = to_f32(inv_d);
    // `(inv_d as f32).is_normal()`, and `inv_d` finite.
    let inv_d_abs = _mm512_cvtps_pd(inv_d32);
    taken &= finite(inv_d)
        & _mm512_cmp_pd_mask::<_CMP_GE_OQ>(abs(inv_d_abs), splat(f64::from(f32::MIN_POSITIVE)))
        & _mm512_cmp_pd_mask::<_CMP_LE_OQ>(abs(inv_d_abs), splat(f64::from(f32::MAX)));
    let near = up(mul(div(splat(z_ref), z_min), splat(1.0 + 2.0 * DEPTH)));
    let f32s = |i: usize| {
        [
            store_f32(to_f32(mul(coefficients[0][i], k))),
            store_f32(to_f32(mul(coefficients[1][i], k))),
            store_f32(to_f32(mul(coefficients[2][i], k))),
        ]
    };
    Lanes {
        a: f32s(0),
        b: f32s(1),
        c: f32s(2),
        m: [
            store_f32(up(m[0])),
            store_f32(up(m[1])),
            store_f32(up(m[2])),
        ],
        sum_margin: store_f32(up(sum_margin)),
        inv_d: store_f32(inv_d32),
        near: store_f32(near),
        ccw,
        x0: store_u32(x0),
        y0: store_u32(y0),
        x1: store_u32(x1),
        y1: store_u32(y1),
        taken,
    }
}
