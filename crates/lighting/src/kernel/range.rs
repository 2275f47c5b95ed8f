//! Vectors of any f32 length (a light 1e20 or 1e-30 away) brought into the
//! range where their squared length neither overflows nor underflows.

use crate::fastmath::Math;

/// `v` scaled by the power of two that brings its largest component into
/// [1, 2), so that its squared length neither overflows nor underflows f32;
/// the scaling is exact. Returns the scaled vector, its squared length
/// raised to the smallest normal (so that an [`super::isa::Isa`] pass may
/// take its `1/√`; a zero vector's stays there, and the callers zero its
/// inverse) and the factor that undoes the scaling.
#[inline(always)]
pub(super) fn range_scaled(v: [f32; 3]) -> ([f32; 3], f32, f32) {
    let largest = v[0].abs().max(v[1].abs()).max(v[2].abs());
    // The biased exponent, kept where both 2^±(exponent − 127) are normal.
    let exponent = (largest.to_bits() >> 23).clamp(1, 253);
    let scale = f32::from_bits((254 - exponent) << 23); // 2^(127 − exponent)
    let unscale = f32::from_bits(exponent << 23); // 1/scale, exactly
    let w = [v[0] * scale, v[1] * scale, v[2] * scale];
    let length2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    (w, length2.max(f32::MIN_POSITIVE), unscale)
}

/// The unit vector along `v`; zero for a zero vector.
#[inline(always)]
pub(super) fn unit<M: Math>(v: [f32; 3]) -> [f32; 3] {
    let (w, length2, _) = range_scaled(v);
    let inverse = if length2 > f32::MIN_POSITIVE {
        M::rsqrt(length2)
    } else {
        0.0
    };
    [w[0] * inverse, w[1] * inverse, w[2] * inverse]
}
