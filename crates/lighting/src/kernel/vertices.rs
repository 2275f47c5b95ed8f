//! A batch in the form the f32 tiers read: f32, structure of arrays,
//! positions recentred and normals scaled near unit length.

use glam::{DVec3, Vec3};

use super::Kernel;
use crate::LightMask;

/// A batch of vertices in the form the f32 tiers read, made by
/// [`Kernel::prepare`]: 12 bytes of normal per vertex, and 12 of position
/// when the lighting uses positions.
#[derive(Clone, Debug, Default)]
pub struct Vertices {
    /// What the preparing kernel did, checked by the kernel that lights.
    pub(super) centre: DVec3,
    pub(super) normalized: bool,
    pub(super) len: usize,
    /// Recentred; empty when the lighting does not depend on position.
    pub(super) positions: [Vec<f32>; 3],
    pub(super) normals: [Vec<f32>; 3],
    /// Per vertex: which lights reach it. None: every light does.
    pub(super) visible: Option<Vec<LightMask>>,
}

impl Vertices {
    /// Says which lights reach each vertex; a light that does not adds only
    /// its ambient term, as a light whose shadow ray is blocked.
    pub fn set_visibility(&mut self, masks: Vec<LightMask>) {
        assert_eq!(masks.len(), self.len);
        self.visible = Some(masks);
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

impl Kernel {
    /// Converts a batch into the f32 form [`Kernel::light`] reads: positions
    /// recentred on this kernel's centre (and only if the lighting uses
    /// them), normals that are about to be normalised scaled by a power of
    /// two to a length near 1, each coordinate in its own array.
    pub fn prepare(&self, positions: &[DVec3], normals: &[DVec3]) -> Vertices {
        assert_eq!(positions.len(), normals.len());
        let mut vertices = Vertices::default();
        let pairs = positions.iter().copied().zip(normals.iter().copied());
        self.prepare_into(pairs, &mut vertices);
        vertices
    }

    /// [`Kernel::prepare`] of `(position, normal)` pairs into the buffers of
    /// `out`, which keep their memory from one call to the next (a renderer
    /// prepares a batch per tile).
    pub fn prepare_into(
        &self,
        vertices: impl ExactSizeIterator<Item = (DVec3, DVec3)>,
        out: &mut Vertices,
    ) {
        let len = vertices.len();
        let positions = if self.depends_on_position { len } else { 0 };
        // Written in place through slices rather than pushed, and not through
        // the vectors, whose lengths would be read again for every value.
        let mut normals = zeroed(&mut out.normals, len);
        let mut recentred = zeroed(&mut out.positions, positions);
        let normal = |n: DVec3| {
            if self.normalize {
                scaled_near_one(n)
            } else {
                n.as_vec3()
            }
        };
        if self.depends_on_position {
            for (i, (p, n)) in vertices.enumerate() {
                set(&mut normals, i, normal(n));
                set(&mut recentred, i, (p - self.centre).as_vec3());
            }
        } else {
            for (i, (_, n)) in vertices.enumerate() {
                set(&mut normals, i, normal(n));
            }
        }
        out.centre = self.centre;
        out.normalized = self.normalize;
        out.len = len;
        out.visible = None;
    }

    /// Whether `vertices` were prepared by a kernel of the same centre and
    /// normal handling.
    pub(super) fn prepared(&self, vertices: &Vertices) -> bool {
        vertices.centre == self.centre
            && vertices.normalized == self.normalize
            && (vertices.positions[0].len() == vertices.len || !self.depends_on_position)
    }
}

/// The three axes of `axes`, each `len` zeros.
fn zeroed(axes: &mut [Vec<f32>; 3], len: usize) -> [&mut [f32]; 3] {
    axes.each_mut().map(|axis| {
        axis.clear();
        axis.resize(len, 0.0);
        axis.as_mut_slice()
    })
}

/// Element `i` of a structure of arrays.
#[inline(always)]
fn set([xs, ys, zs]: &mut [&mut [f32]; 3], i: usize, v: Vec3) {
    (xs[i], ys[i], zs[i]) = (v.x, v.y, v.z);
}

/// `n` scaled by the power of two that brings its largest component into
/// [1, 2), as f32: the scaling is exact, so the direction is `n`'s, and the
/// kernel normalises it without range checks. Zero stays zero.
fn scaled_near_one(n: DVec3) -> Vec3 {
    let largest = n.abs().max_element();
    // A normal near unit length, the usual one, by the shortest way.
    if (0.5..2.0).contains(&largest) {
        return if largest < 1.0 { n * 2.0 } else { n }.as_vec3();
    }
    if largest == 0.0 {
        return Vec3::ZERO;
    }
    // Out of the subnormals first, so that the exponent field is the exponent.
    let (n, largest) = if largest < f64::MIN_POSITIVE {
        (n * 2f64.powi(600), largest * 2f64.powi(600))
    } else {
        (n, largest)
    };
    let exponent = (largest.to_bits() >> 52) as i64 - 1023;
    let two_to_minus = |k: i64| f64::from_bits(((1023 - k) as u64) << 52);
    // In two factors, each within f64's normal range.
    let half = exponent / 2;
    (n * two_to_minus(half) * two_to_minus(exponent - half)).as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The scaling is by the power of two `2^-floor(log2(largest))`, on the
    /// short way for normals near unit length as on the long one.
    #[test]
    fn scaled_near_one_scales_by_the_power_of_two_of_the_largest_component() {
        let scales = [
            1e-300, 1e-5, 0.25, 0.5, 0.75, 0.999_999, 1.0, 1.5, 1.999_999, 2.0, 3.0, 1e300,
        ];
        for scale in scales {
            let n = DVec3::new(0.3, -1.0, 0.2) * scale;
            let exponent = n.abs().max_element().log2().floor() as i32;
            let want = (n * 2f64.powi(-exponent)).as_vec3();
            assert_eq!(scaled_near_one(n), want, "scale {scale}");
            assert!((1.0..2.0).contains(&want.abs().max_element()));
        }
        assert_eq!(scaled_near_one(DVec3::ZERO), Vec3::ZERO);
    }
}
