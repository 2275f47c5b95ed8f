//! One block of vertices as structure of arrays: the working set of the
//! vertex loops, loaded from a batch and lit light by light.

use super::isa::Isa;
use super::range::range_scaled;
use super::variant::Variant;
use super::{Kernel, Vertices, Viewer32};
use crate::LightMask;
use crate::fastmath::Math;

/// Vertices per block: the working set stays in L1.
pub(super) const BLOCK: usize = 64;

/// One block of vertices, structure of arrays. Every array starts on a
/// cache line (each is a multiple of 64 bytes, the masks come last), so
/// that no 64-byte vector load or store of a pass is split across two.
#[derive(Clone)]
#[repr(C, align(64))]
pub(super) struct Block {
    /// `V`, recentred.
    pub p: [[f32; BLOCK]; 3],
    /// `n` as the lighting sees it (normalised if asked).
    pub n: [[f32; BLOCK]; 3],
    /// `VP_e`, for a local viewer.
    pub vp_e: [[f32; BLOCK]; 3],
    /// `n·VP_e`, for the fast tier's specular terms of lights at a point
    /// (see `fast_point`).
    pub n_dot_eye: [f32; BLOCK],
    /// The sum of the terms that are not specular, and of the specular ones
    /// unless they are clamped on their own.
    pub primary: [[f32; BLOCK]; 3],
    /// The specular terms, where they are clamped on their own (else they
    /// go to `primary`, and this is not read).
    pub secondary: [[f32; BLOCK]; 3],
    /// Per light at a point: `VP_pli` (in the fast tier's passes of
    /// `fast_point`, `P_pli − V`, not normalised).
    pub vp_pli: [[f32; BLOCK]; 3],
    /// Per light at a point, in the fast tier's passes: `n·(P_pli − V)`.
    pub n_dot_d: [f32; BLOCK],
    /// Per light at a point, in the fast tier's passes: `n·u`.
    pub n_dot_u: [f32; BLOCK],
    /// Per light at a point: `att_i · spot_i` (before the spot's power).
    pub scale: [f32; BLOCK],
    /// A cosine per vertex, specular or spot (`cos²` negative where
    /// `cos ≤ 0`), raised by [`super::power::power_block`] into `power`.
    pub sin2: [f32; BLOCK],
    pub cos2: [f32; BLOCK],
    pub power: [f32; BLOCK],
    /// What multiplies the specular power: visibility, `f_i`, attenuation
    /// and spot.
    pub gate: [f32; BLOCK],
    /// Per light at a point: `|P_pli − V|²`, scaled into range.
    pub distance2: [f32; BLOCK],
    /// Its `1/√`.
    pub inverse_distance: [f32; BLOCK],
    /// The factor 2^(exponent − 127) that undoes the scaling of
    /// `distance2` (see [`range_scaled`]).
    pub unscale: [f32; BLOCK],
    /// Per attenuated light: `k0 + k1·d + k2·d²`, clamped into the range
    /// whose reciprocal is normal.
    pub denominator: [f32; BLOCK],
    /// Its reciprocal.
    pub inverse_denominator: [f32; BLOCK],
    /// Per light at a point, for an infinite viewer: `|ĥ|²`.
    pub half2: [f32; BLOCK],
    /// Its reciprocal.
    pub inverse_half2: [f32; BLOCK],
    /// Per light: 1 where the light reaches the vertex, else 0.
    pub visible: [f32; BLOCK],
    /// The vertices' visibility masks, if they have them.
    pub masks: Option<[LightMask; BLOCK]>,
}

// The arrays above are whole cache lines.
const _: () = assert!((BLOCK * 4).is_multiple_of(64));

impl Default for Block {
    fn default() -> Self {
        let zero = [[0.0; BLOCK]; 3];
        Self {
            p: zero,
            n: zero,
            vp_e: zero,
            n_dot_eye: [0.0; BLOCK],
            primary: zero,
            secondary: zero,
            vp_pli: zero,
            n_dot_d: [0.0; BLOCK],
            n_dot_u: [0.0; BLOCK],
            scale: [0.0; BLOCK],
            sin2: [0.0; BLOCK],
            cos2: [0.0; BLOCK],
            power: [0.0; BLOCK],
            gate: [0.0; BLOCK],
            distance2: [0.0; BLOCK],
            inverse_distance: [0.0; BLOCK],
            unscale: [0.0; BLOCK],
            denominator: [0.0; BLOCK],
            inverse_denominator: [0.0; BLOCK],
            half2: [0.0; BLOCK],
            inverse_half2: [0.0; BLOCK],
            masks: None,
            visible: [1.0; BLOCK],
        }
    }
}

impl Block {
    /// Loads the vertices of `range` (at most [`BLOCK`]); the lanes past its
    /// end are zero normals at the batch's last position.
    #[inline(always)]
    pub fn load<V: Variant>(
        &mut self,
        kernel: &Kernel,
        vertices: &Vertices,
        range: std::ops::Range<usize>,
    ) {
        let count = range.len();
        if count < BLOCK {
            self.p = [[0.0; BLOCK]; 3];
            self.n = [[0.0; BLOCK]; 3];
        }
        // A full block is copied with a size the compiler knows.
        let copy = |to: &mut [f32; BLOCK], from: &[f32]| match <&[f32; BLOCK]>::try_from(from) {
            Ok(full) => *to = *full,
            Err(_) => to[..count].copy_from_slice(from),
        };
        if kernel.depends_on_position {
            for axis in 0..3 {
                copy(&mut self.p[axis], &vertices.positions[axis][range.clone()]);
                // Lanes past the batch repeat its last vertex, so that they
                // are as far from each light as a real one: a lane at the
                // origin would send the block down the scaled path of a
                // light there.
                let last = self.p[axis][count - 1];
                self.p[axis][count..].fill(last);
            }
        }
        for axis in 0..3 {
            copy(&mut self.n[axis], &vertices.normals[axis][range.clone()]);
        }
        self.load_visibility(vertices, range);
        if !V::RAW {
            self.normalize_normals::<V::I>();
        }
        if let (true, Viewer32::Local(eye)) = (V::LOCAL, kernel.viewer) {
            self.local_eye_directions::<V::I>(eye.to_array());
        }
        if V::M::FAST_POINT && V::SPEC && !V::PHONG && !V::RAW && kernel.depends_on_position {
            self.normals_dot_eye::<V>(kernel);
        }
    }

    /// `n·VP_e` of every lane into `n_dot_eye`.
    #[inline(always)]
    fn normals_dot_eye<V: Variant>(&mut self, kernel: &Kernel) {
        let eye = match kernel.viewer {
            Viewer32::Infinite(dir) => dir.to_array(),
            Viewer32::Local(_) => [0.0; 3],
        };
        for i in 0..BLOCK {
            let vp_e = if V::LOCAL {
                [self.vp_e[0][i], self.vp_e[1][i], self.vp_e[2][i]]
            } else {
                eye
            };
            let n = [self.n[0][i], self.n[1][i], self.n[2][i]];
            self.n_dot_eye[i] = n[2].mul_add(vp_e[2], n[1].mul_add(vp_e[1], n[0] * vp_e[0]));
        }
    }

    /// The visibility masks of `range`, if the batch has them.
    #[inline(always)]
    fn load_visibility(&mut self, vertices: &Vertices, range: std::ops::Range<usize>) {
        // A block may come from a batch with other masks (see `task`).
        match &vertices.visible {
            Some(visible) => {
                let mut masks = [LightMask::MAX; BLOCK];
                masks[..range.len()].copy_from_slice(&visible[range]);
                self.masks = Some(masks);
            }
            // `visible` is all ones but where a block with masks wrote it.
            None => {
                if self.masks.take().is_some() {
                    self.visible = [1.0; BLOCK];
                }
            }
        }
    }

    /// `n` to unit length. The normals were scaled near 1 by
    /// [`Kernel::prepare`]: no range checks. Unit to an ULP or two in every
    /// tier, once per vertex, so that the fast tier's cosines of whole
    /// powers need no correction for their length once per light.
    #[inline(always)]
    fn normalize_normals<I: Isa>(&mut self) {
        // Zero stays zero: its `length2` is raised to the smallest normal.
        I::normalize(&mut self.n);
    }

    /// `VP_e`, the unit vector from each vertex to the local viewer at
    /// `eye`; zero for a vertex at the eye.
    #[inline(always)]
    fn local_eye_directions<I: Isa>(&mut self, eye: [f32; 3]) {
        let mut distance2 = [0.0; BLOCK];
        for i in 0..BLOCK {
            let d = [
                eye[0] - self.p[0][i],
                eye[1] - self.p[1][i],
                eye[2] - self.p[2][i],
            ];
            let (w, scaled2, _) = range_scaled(d);
            for axis in 0..3 {
                self.vp_e[axis][i] = w[axis];
            }
            distance2[i] = scaled2;
        }
        let mut inverse_distance = [0.0; BLOCK];
        I::rsqrt(&distance2, &mut inverse_distance);
        for i in 0..BLOCK {
            let inverse = if distance2[i] > f32::MIN_POSITIVE {
                inverse_distance[i]
            } else {
                0.0
            };
            for axis in 0..3 {
                self.vp_e[axis][i] *= inverse;
            }
        }
    }

    /// The back side's normals, and their `n·VP_e`.
    #[inline(always)]
    pub fn negate_normals(&mut self) {
        for axis in self.n.iter_mut().chain([&mut self.n_dot_eye]) {
            for v in axis.iter_mut() {
                *v = -*v;
            }
        }
    }

    /// Lane `i`'s visibility of light `index`, from the masks if the block
    /// has them.
    #[inline(always)]
    pub fn set_visible(&mut self, index: usize) {
        if let Some(masks) = &self.masks {
            for i in 0..BLOCK {
                self.visible[i] = ((masks[i] >> index) & 1) as f32;
            }
        }
    }
}
