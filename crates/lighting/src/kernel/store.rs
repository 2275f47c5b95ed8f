//! The fused store: a block's sums clamped as GL clamps them, interleaved
//! with alpha into the batch's colours.

use std::mem::MaybeUninit;

use glam::Vec4;

use super::block::{BLOCK, Block};

impl Block {
    /// Writes the clamped colours of the first `out.len()` lanes,
    /// interleaved with alpha: one loop that vectorises, after the clamp of
    /// each sum of a separate specular colour. The colours go through the
    /// cache: the response encoder or the renderer reads them next, and
    /// non-temporal stores measured no faster (see `docs/design.md`).
    #[inline(always)]
    pub fn store(&mut self, separate_specular: bool, alpha: f32, out: &mut [MaybeUninit<Vec4>]) {
        if separate_specular {
            for c in 0..3 {
                let (primary, secondary) = (&mut self.primary[c], &self.secondary[c]);
                for i in 0..BLOCK {
                    primary[i] = primary[i].clamp(0.0, 1.0) + secondary[i].clamp(0.0, 1.0);
                }
            }
        }
        // SAFETY: a `Vec4` is four f32 (x, y, z, w) and nothing else.
        let out: &mut [MaybeUninit<f32>] =
            unsafe { std::slice::from_raw_parts_mut(out.as_mut_ptr().cast(), out.len() * 4) };
        // A full block has a trip count the vectoriser knows.
        match <&mut [MaybeUninit<f32>; 4 * BLOCK]>::try_from(&mut *out) {
            Ok(full) => self.interleave(alpha, full),
            Err(_) => self.interleave(alpha, out),
        }
    }

    #[inline(always)]
    fn interleave(&self, alpha: f32, out: &mut [MaybeUninit<f32>]) {
        for i in 0..out.len() / 4 {
            for c in 0..3 {
                out[4 * i + c].write(self.primary[c][i].clamp(0.0, 1.0));
            }
            out[4 * i + 3].write(alpha);
        }
    }
}
