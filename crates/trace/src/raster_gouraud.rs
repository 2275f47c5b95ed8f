//! One sample per pixel with Gouraud shading: a pixel's bytes straight from
//! the rasterizer's decision, without its ray, its exact test or its hit.
//!
//! Where the rasterizer has decided which triangle a pixel's centre ray
//! hits ([`crate::raster::Decisions`]), the traced pixel is
//! `encode(α·c_0 + β·c_1 + γ·c_2)`, with `(β, γ) = (u, v)` the exact test's
//! barycentrics and `α = 1 − u − v`. The barycentrics are the edge
//! functions over their sum (see [`crate::raster`]): `b_i = F_i / S` with
//! `S = F_0 + F_1 + F_2`. Here they are evaluated in f64 lanes from the
//! triangle's f64 edge functions ([`ExactEdges`]), each within `m_i` of the
//! exact test's `F*_i`. With `M = m_0 + m_1 + m_2`,
//!
//! `b_i − b*_i = (F_i − F*_i)/S + b*_i·(S* − S)/S`, so
//! `Σ |b_i − b*_i| ≤ (M/S)·(1 + Σ b*_i) = 2·M/S`
//!
//! for a hit (every `b*_i ≥ 0`, their sum 1), and each channel of the
//! colour lies within `2·(M/S)·max_i |c_i|` of the traced one, before the
//! roundings of either evaluation (a few ulps, covered by an absolute
//! 2^-40 and a factor of four on the bound). When both ends of that
//! interval, clamped and scaled as [`crate::film::encode`] does, fall in the same
//! byte, the byte is the traced pixel's; otherwise (a colour within the
//! bound of a boundary between bytes) the pixel is traced. `M/S` grows as a
//! triangle's size shrinks against its distance: at 1920×1080, one pixel
//! in 7,000 is traced for that reason on a sphere of 102,400 triangles, one
//! in 700 with 10^6. The image is the traced image, byte for byte, with
//! linear encoding; sRGB's curve is left to the traced pixels.

// The lane loops index several arrays by lane on purpose: that is the
// structure of arrays the vectoriser needs.
#![allow(clippy::needless_range_loop)]

use glam::DVec4;

use crate::raster::{ExactEdges, LANES};

/// A triangle ready for its pixels: its edge functions, the colours of its
/// corners on the side seen, and the byte of its alpha where that is one
/// for the whole triangle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Corners {
    edges: ExactEdges,
    colors: [DVec4; 3],
    /// Where the corners' alphas are one value `a`: the traced alpha,
    /// `α·a + β·a + γ·a`, is `a·(α + β + γ)` within a few ulps, and
    /// `α + β + γ = (1 − u − v) + u + v` is 1 within as few, whatever the
    /// barycentrics' error; so its byte is that of `a` within
    /// [`ROUNDING`], where that is one byte.
    alpha: Option<u32>,
}

/// The factor on the bound `2·M/S` of the barycentrics' error.
const SAFETY: f64 = 4.0;

/// The absolute part of a channel's bound, for the roundings of the two
/// evaluations of the colour (each a few ulps of values of order 1).
const ROUNDING: f64 = 1.0 / 1_099_511_627_776.0;

/// 2^52: a sum with it holds an integer of at most 2^52 in its low bits.
const TWO_52: f64 = 4_503_599_627_370_496.0;

/// The largest `M/S` the bound is used at: past it, the pixel is traced.
const MAX_RELATIVE: f64 = 1.0 / 1024.0;

/// Pixel centres, in lanes: their coordinates in the full image.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Samples {
    pub x: [f64; LANES],
    pub y: [f64; LANES],
}

/// Writes the RGBA8 bytes (R in the lowest byte) of `corners`' triangle
/// at the lanes of `samples` in the mask `lanes` into the same lanes of
/// `out`, where they are surely the traced pixel's; returns the lanes
/// written, as a mask. (The caller gives only lanes the triangle holds.)
pub(crate) type BytesFn = fn(&Corners, &Samples, u32, &mut [u32; LANES]) -> u32;

/// The bytes `film::encode` gives the ends of `[color − bound, color +
/// bound]`, as integers in f64: the same byte where the interval holds
/// one. (As `film::encode`: clamped, ½ added and truncated, the floor of
/// these positive values, the ends moved out by far more than the f64
/// rounding of `255·c + ½`.)
#[inline(always)]
fn byte_range(color: f64, bound: f64) -> (f64, f64) {
    let lo = (color - bound).clamp(0.0, 1.0);
    let hi = (color + bound).clamp(0.0, 1.0);
    let low = (255.0 * lo + (0.5 - ROUNDING)).floor();
    let high = (255.0 * hi + (0.5 + ROUNDING)).floor();
    (low, high)
}

impl Corners {
    /// The triangle of `edges` with the corner colours `colors`.
    pub(crate) fn new(edges: ExactEdges, colors: [DVec4; 3]) -> Self {
        let a = colors[0].w;
        let uniform = colors.iter().all(|c| c.w == a);
        let (low, high) = byte_range(a, ROUNDING * (1.0 + a.abs()));
        Self {
            edges,
            colors,
            alpha: (uniform && low == high).then_some((low as u32) << 24),
        }
    }

    #[inline(always)]
    fn bytes(&self, samples: &Samples, lanes: u32, out: &mut [u32; LANES]) -> u32 {
        match self.alpha {
            Some(alpha) => self.channel_bytes::<3>(samples, lanes, alpha, out),
            None => self.channel_bytes::<4>(samples, lanes, 0, out),
        }
    }

    /// [`Self::bytes`], the first `CHANNELS` channels interpolated and the
    /// bytes `known` of the others or'ed in.
    #[inline(always)]
    fn channel_bytes<const CHANNELS: usize>(
        &self,
        samples: &Samples,
        lanes: u32,
        known: u32,
        out: &mut [u32; LANES],
    ) -> u32 {
        let [e0, e1, e2] = self.edges.coefficients;
        let margin = self.edges.margin[0] + self.edges.margin[1] + self.edges.margin[2];
        let [c0, c1, c2] = self.colors.map(|c| c.to_array());
        let largest: [f64; 4] =
            std::array::from_fn(|ch| c0[ch].abs().max(c1[ch].abs()).max(c2[ch].abs()));
        let mut written = [false; LANES];
        for l in 0..LANES {
            let (x, y) = (samples.x[l], samples.y[l]);
            let f0 = e0[0] * x + e0[1] * y + e0[2];
            let f1 = e1[0] * x + e1[1] * y + e1[2];
            let f2 = e2[0] * x + e2[1] * y + e2[2];
            let inv = 1.0 / (f0 + f1 + f2);
            let relative = margin * inv;
            // (A NaN fails too.)
            let mut sure = (0.0..=MAX_RELATIVE).contains(&relative);
            let spread = SAFETY * 2.0 * relative;
            let (b0, b1, b2) = (f0 * inv, f1 * inv, f2 * inv);
            let mut rgba = known;
            for ch in 0..CHANNELS {
                let color = b0 * c0[ch] + b1 * c1[ch] + b2 * c2[ch];
                let bound = spread * largest[ch] + ROUNDING * (1.0 + largest[ch]);
                let (low, high) = byte_range(color, bound);
                sure &= low == high;
                // The integer in [0, 255] from the low bits of its sum with
                // 2^52 (a conversion that stays in the vector lanes).
                rgba |= ((low + TWO_52).to_bits() as u32) << (8 * ch);
            }
            // Every lane written, its old value or its new one chosen by
            // the mask: a select in vector lanes.
            let write = sure & (lanes >> l & 1 != 0);
            out[l] = if write { rgba } else { out[l] };
            written[l] = write;
        }
        (0..LANES).fold(0, |mask, l| mask | u32::from(written[l]) << l)
    }
}

/// The widest build of [`Corners::bytes`] the CPU runs.
pub(crate) fn dispatch() -> BytesFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f") && std::is_x86_feature_detected!("avx512dq") {
            return |c, s, l, o| {
                // SAFETY: the CPU has AVX-512F and DQ, checked just above.
                unsafe { bytes_avx512(c, s, l, o) }
            };
        }
        if std::is_x86_feature_detected!("avx2") {
            return |c, s, l, o| {
                // SAFETY: the CPU has AVX2, checked just above.
                unsafe { bytes_avx2(c, s, l, o) }
            };
        }
    }
    |c, s, l, o| c.bytes(s, l, o)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq")]
fn bytes_avx512(corners: &Corners, samples: &Samples, lanes: u32, out: &mut [u32; LANES]) -> u32 {
    corners.bytes(samples, lanes, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn bytes_avx2(corners: &Corners, samples: &Samples, lanes: u32, out: &mut [u32; LANES]) -> u32 {
    corners.bytes(samples, lanes, out)
}

/// The setup of the first lane of `todo` (not empty) and the lanes of
/// `todo` whose triangle it is too, as a mask.
pub(crate) fn next_triangle(best: &[u32; LANES], todo: u32) -> (u32, u32) {
    let setup = best[todo.trailing_zeros() as usize];
    let mut same = 0u32;
    for l in 0..LANES {
        same |= u32::from(best[l] == setup) << l;
    }
    (setup, same & todo)
}

/// Whether `film::encode` of linear colours is what this module computes.
pub(crate) fn applies(encoding: crate::scene::Encoding) -> bool {
    encoding == crate::scene::Encoding::Linear
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film;
    use crate::raster::LANE_MASK;

    /// A triangle whose edge functions are the barycentrics themselves,
    /// over pixel coordinates in [0, 1]: `F_1 = x`, `F_2 = y`,
    /// `F_0 = 1 − x − y`.
    fn unit(colors: [DVec4; 3], margin: f64) -> Corners {
        let edges = ExactEdges {
            coefficients: [[-1.0, -1.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            margin: [margin; 3],
        };
        Corners::new(edges, colors)
    }

    fn lanes(points: &[(f64, f64)]) -> Samples {
        let mut samples = Samples::default();
        for (l, &(x, y)) in points.iter().cycle().take(LANES).enumerate() {
            samples.x[l] = x;
            samples.y[l] = y;
        }
        samples
    }

    #[test]
    fn the_bytes_are_those_of_the_traced_formula_when_sure() {
        // The alphas differ, are one value, and are one value past 1.
        for alphas in [[1.0, 1.0, 0.5], [0.6; 3], [1.3; 3]] {
            let colors = [
                DVec4::new(0.9, 0.1, 0.3, alphas[0]),
                DVec4::new(0.2, 0.7, 0.35, alphas[1]),
                DVec4::new(0.05, 0.4, 1.3, alphas[2]),
            ];
            traced_where_sure(colors);
        }
    }

    fn traced_where_sure(colors: [DVec4; 3]) {
        let corners = unit(colors, 1e-13);
        // Points inside the triangle, on a grid that misses its edges.
        let points: Vec<(f64, f64)> = (0..40)
            .flat_map(|i| {
                (0..40 - i).map(move |j| ((i as f64 + 0.3) / 41.0, (j as f64 + 0.3) / 41.0))
            })
            .collect();
        let mut sure = 0;
        for group in points.chunks(LANES) {
            let mut bytes = [0; LANES];
            let written = dispatch()(&corners, &lanes(group), LANE_MASK, &mut bytes);
            for (l, &(u, v)) in group.iter().enumerate() {
                let traced = (1.0 - u - v) * colors[0] + u * colors[1] + v * colors[2];
                if written >> l & 1 != 0 {
                    let expected = film::encode(traced, crate::scene::Encoding::Linear);
                    assert_eq!(bytes[l].to_le_bytes(), expected, "at ({u}, {v})");
                    sure += 1;
                }
            }
        }
        // Only a colour on a boundary between bytes is left to the tracer.
        assert!(sure + 8 >= points.len(), "{sure} of {} sure", points.len());
    }

    #[test]
    fn only_the_lanes_asked_for_are_written() {
        let corners = unit([DVec4::new(0.31, 0.62, 0.93, 1.0); 3], 1e-13);
        let mut out = [7; LANES];
        let asked = 0b1010_0110;
        let written = dispatch()(&corners, &lanes(&[(0.25, 0.25)]), asked, &mut out);
        assert_eq!(written, asked, "every lane asked for is sure");
        for (l, &byte) in out.iter().enumerate() {
            assert_eq!(byte != 7, asked >> l & 1 != 0, "lane {l}");
        }
    }

    #[test]
    fn a_colour_at_a_rounding_boundary_is_left_to_the_tracer() {
        // Red is ½ at every point: 255·½ + ½ = 128, on the boundary
        // between two bytes.
        let red = 0.5;
        let colors = [DVec4::new(red, 0.0, 0.0, 1.0); 3];
        let corners = unit(colors, 1e-13);
        let mut out = [0; LANES];
        assert_eq!(
            dispatch()(&corners, &lanes(&[(0.25, 0.25)]), LANE_MASK, &mut out) & 1,
            0
        );
        // So does an alpha on a boundary, one value at every corner.
        let corners = unit([DVec4::new(0.3, 0.3, 0.3, 0.5); 3], 1e-13);
        assert_eq!(
            dispatch()(&corners, &lanes(&[(0.25, 0.25)]), LANE_MASK, &mut out) & 1,
            0
        );
        // A margin as wide as the triangle leaves every pixel to the tracer.
        let corners = unit([DVec4::splat(0.3); 3], 0.01);
        assert_eq!(
            dispatch()(&corners, &lanes(&[(0.25, 0.25)]), LANE_MASK, &mut out) & 1,
            0
        );
        assert_eq!(out, [0; LANES], "no lane is written where none is sure");
    }

    #[test]
    fn the_lanes_of_one_triangle_are_found_together() {
        let mut best = [9; LANES];
        best[..5].copy_from_slice(&[7, 7, 3, 7, 7]);
        // Lane 1 is not to do; lane 4 is, but lane 15's 9 is not 7.
        let todo = 0b1101 | 1 << 4 | 1 << 15;
        assert_eq!(next_triangle(&best, todo), (7, 0b1_1001));
        assert_eq!(next_triangle(&best, 0b100), (3, 0b100));
        assert_eq!(next_triangle(&best, 1 << 15), (9, 1 << 15));
    }
}
