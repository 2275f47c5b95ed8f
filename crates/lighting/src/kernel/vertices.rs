//! A batch in the form the f32 tiers read: f32, structure of arrays,
//! positions recentred and normals scaled near unit length.

use glam::{DVec3, Vec3};

use super::{InstructionSet, Kernel, TASK_VERTICES};
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
    /// The least and the greatest recentred position on each axis, where
    /// the lighting uses positions and every one is finite: what
    /// [`Kernel::lights_in_range`] bounds distances with.
    pub(super) bounds: Option<[Vec3; 2]>,
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
    /// two to a length near 1, each coordinate in its own array. A batch of
    /// more than one lighting task's [`TASK_VERTICES`] is converted in
    /// halves on the current rayon pool, down to pieces of at most that
    /// many; a smaller one on the calling thread.
    pub fn prepare(&self, positions: &[DVec3], normals: &[DVec3]) -> Vertices {
        assert_eq!(positions.len(), normals.len());
        let len = positions.len();
        let mut out = Vertices::default();
        let mut normals_out = sized(&mut out.normals, len);
        let mut positions_out = sized(&mut out.positions, self.positions_len(len));
        let bounds = self.prepare_halves(positions, normals, &mut normals_out, &mut positions_out);
        self.finish(&mut out, len, bounds);
        out
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
        let mut normals = sized(&mut out.normals, len);
        let mut recentred = sized(&mut out.positions, self.positions_len(len));
        let bounds = self.prepare_pairs(vertices, &mut normals, &mut recentred);
        self.finish(out, len, bounds);
    }

    /// [`Kernel::prepare_into`] of vertices given an array per axis:
    /// vertex `i` at `positions[axis][i]` with the normal
    /// `normals[axis][i]`, every array of one length. The same f32 arrays
    /// to the bit, computed in vector lanes (the build of
    /// [`InstructionSet::chosen`]).
    pub fn prepare_lanes(&self, positions: [&[f64]; 3], normals: [&[f64]; 3], out: &mut Vertices) {
        self.prepare_lanes_on(InstructionSet::chosen(), positions, normals, out);
    }

    /// [`Self::prepare_lanes`] by the build `isa`, one the CPU runs.
    fn prepare_lanes_on(
        &self,
        isa: InstructionSet,
        positions: [&[f64]; 3],
        normals: [&[f64]; 3],
        out: &mut Vertices,
    ) {
        assert!(isa.runs_here(), "the {isa} build on a CPU that runs it");
        let len = normals[0].len();
        assert!(
            positions
                .iter()
                .chain(&normals)
                .all(|axis| axis.len() == len),
            "an array per axis, of one length"
        );
        let arrays = Arrays { positions, normals };
        let bounds = match isa {
            #[cfg(target_arch = "x86_64")]
            InstructionSet::Avx512 => {
                // SAFETY: the CPU runs AVX-512F, AVX2 and FMA (asserted
                // above).
                unsafe { lanes_avx512(self, arrays, out) }
            }
            #[cfg(target_arch = "x86_64")]
            InstructionSet::Avx2 => {
                // SAFETY: the CPU runs AVX2 and FMA, as above.
                unsafe { lanes_avx2(self, arrays, out) }
            }
            _ => self.prepare_arrays(arrays, out),
        };
        self.finish(out, len, bounds);
    }

    /// [`Self::prepare_pairs`] of the arrays of [`Self::prepare_lanes`],
    /// written for vector lanes: each normal scaled as
    /// [`scaled_near_one`] scales one near unit length, the others (none,
    /// for the normals a renderer interpolates) by that function itself
    /// afterwards; the bounds kept per lane and joined at the end (the
    /// least and greatest of finite values, whatever their order).
    #[inline(always)]
    fn prepare_arrays(&self, Arrays { positions, normals }: Arrays, out: &mut Vertices) -> Bounds {
        let len = normals[0].len();
        let normals_out = &mut sized(&mut out.normals, len);
        let recentred = &mut sized(&mut out.positions, self.positions_len(len));
        let [nx, ny, nz] = normals.map(|axis| &axis[..len]);
        {
            let [ox, oy, oz] = normals_out.each_mut().map(|axis| &mut axis[..len]);
            if self.normalize {
                let mut far = false;
                for i in 0..len {
                    let (x, y, z) = (nx[i], ny[i], nz[i]);
                    // `DVec3::max_element` of the magnitudes, as
                    // `scaled_near_one` takes it.
                    let max = |a: f64, b: f64| if a > b { a } else { b };
                    let largest = max(x.abs(), max(y.abs(), z.abs()));
                    far |= !(0.5..2.0).contains(&largest);
                    let scale = if largest < 1.0 { 2.0 } else { 1.0 };
                    (ox[i], oy[i], oz[i]) =
                        ((x * scale) as f32, (y * scale) as f32, (z * scale) as f32);
                }
                if far {
                    for i in 0..len {
                        let n = DVec3::new(nx[i], ny[i], nz[i]);
                        if !(0.5..2.0).contains(&n.abs().max_element()) {
                            set(normals_out, i, scaled_near_one(n));
                        }
                    }
                }
            } else {
                for i in 0..len {
                    (ox[i], oy[i], oz[i]) = (nx[i] as f32, ny[i] as f32, nz[i] as f32);
                }
            }
        }
        let mut bounds = Bounds::EMPTY;
        if !self.depends_on_position {
            return bounds;
        }
        for (axis, (from, to)) in positions.iter().zip(recentred.iter_mut()).enumerate() {
            let (from, to) = (&from[..len], &mut to[..len]);
            let centre = self.centre[axis];
            for i in 0..len {
                to[i] = (from[i] - centre) as f32;
            }
            // Each lane's least and greatest, then theirs.
            let mut lo = [f32::INFINITY; BOUND_LANES];
            let mut hi = [f32::NEG_INFINITY; BOUND_LANES];
            let mut finite = [true; BOUND_LANES];
            let lanes = to.chunks_exact(BOUND_LANES);
            let rest = lanes.remainder();
            for chunk in lanes {
                for l in 0..BOUND_LANES {
                    lo[l] = lo[l].min(chunk[l]);
                    hi[l] = hi[l].max(chunk[l]);
                    finite[l] &= chunk[l].is_finite();
                }
            }
            for (l, &r) in rest.iter().enumerate() {
                lo[l] = lo[l].min(r);
                hi[l] = hi[l].max(r);
                finite[l] &= r.is_finite();
            }
            bounds.lo[axis] = lo.iter().fold(f32::INFINITY, |a, &b| a.min(b));
            bounds.hi[axis] = hi.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
            bounds.finite &= finite.iter().all(|&f| f);
        }
        bounds
    }

    /// How many positions a batch of `len` vertices keeps.
    fn positions_len(&self, len: usize) -> usize {
        if self.depends_on_position { len } else { 0 }
    }

    /// [`Kernel::prepare`] in halves on the rayon pool, down to
    /// [`TASK_VERTICES`] vertices each.
    fn prepare_halves(
        &self,
        positions: &[DVec3],
        normals: &[DVec3],
        normals_out: &mut [&mut [f32]; 3],
        positions_out: &mut [&mut [f32]; 3],
    ) -> Bounds {
        let len = positions.len();
        if len <= TASK_VERTICES {
            let pairs = positions.iter().copied().zip(normals.iter().copied());
            return self.prepare_pairs(pairs, normals_out, positions_out);
        }
        let mid = len / 2;
        let (positions_lo, positions_hi) = positions.split_at(mid);
        let (normals_lo, normals_hi) = normals.split_at(mid);
        let (mut n_lo, mut n_hi) = split_axes(normals_out, mid);
        let (mut p_lo, mut p_hi) = split_axes(positions_out, mid);
        let (lo, hi) = rayon::join(
            || self.prepare_halves(positions_lo, normals_lo, &mut n_lo, &mut p_lo),
            || self.prepare_halves(positions_hi, normals_hi, &mut n_hi, &mut p_hi),
        );
        lo.union(hi)
    }

    /// The f32 form of `vertices` into the arrays `normals` and
    /// `recentred` (empty where the lighting does not use positions), and
    /// the bounds of the recentred positions.
    fn prepare_pairs(
        &self,
        vertices: impl Iterator<Item = (DVec3, DVec3)>,
        normals: &mut [&mut [f32]; 3],
        recentred: &mut [&mut [f32]; 3],
    ) -> Bounds {
        let normal = |n: DVec3| {
            if self.normalize {
                scaled_near_one(n)
            } else {
                n.as_vec3()
            }
        };
        let mut bounds = Bounds::EMPTY;
        if self.depends_on_position {
            for (i, (p, n)) in vertices.enumerate() {
                set(normals, i, normal(n));
                let r = (p - self.centre).as_vec3();
                bounds.add(r);
                set(recentred, i, r);
            }
        } else {
            for (i, (_, n)) in vertices.enumerate() {
                set(normals, i, normal(n));
            }
        }
        bounds
    }

    /// What every prepared batch records beside its arrays.
    fn finish(&self, out: &mut Vertices, len: usize, bounds: Bounds) {
        out.bounds = (self.depends_on_position && bounds.finite && len > 0)
            .then_some([bounds.lo, bounds.hi]);
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

impl Kernel {
    /// The lights at a point whose squared distance to every vertex of
    /// `vertices` is well within `UNSCALED_DISTANCE2`, a bit each (bit `i`
    /// for light `i`): the fast tier's one pass need not test their lanes.
    /// The distances are bounded by the box of the recentred positions, in
    /// f64 from the f32 values the lanes read; a lane's f32 `|d|²` is
    /// within a few ULP of its exact value, and the margin is a factor of 2.
    pub(super) fn lights_in_range(&self, vertices: &Vertices) -> LightMask {
        let Some([lo, hi]) = vertices.bounds else {
            return 0;
        };
        let range = super::positional::UNSCALED_DISTANCE2;
        let (least, greatest) = (2.0 * f64::from(range.start), 0.5 * f64::from(range.end));
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        self.sources
            .iter()
            .enumerate()
            .fold(0, |mask, (i, source)| match source {
                super::Source::Positional { p_pli, .. } => {
                    let p = p_pli.as_dvec3();
                    let near = (lo - p).max(p - hi).max(DVec3::ZERO);
                    let far = (lo - p).abs().max((hi - p).abs());
                    let within = near.length_squared() >= least && far.length_squared() <= greatest;
                    mask | (LightMask::from(within) << i)
                }
                super::Source::Directional { .. } => mask,
            })
    }
}

/// The lanes [`Kernel::prepare_lanes`] keeps the bounds in.
const BOUND_LANES: usize = 16;

/// The vertices of [`Kernel::prepare_lanes`], an array per axis.
#[derive(Clone, Copy)]
struct Arrays<'a> {
    positions: [&'a [f64]; 3],
    normals: [&'a [f64]; 3],
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn lanes_avx512(kernel: &Kernel, arrays: Arrays, out: &mut Vertices) -> Bounds {
    kernel.prepare_arrays(arrays, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn lanes_avx2(kernel: &Kernel, arrays: Arrays, out: &mut Vertices) -> Bounds {
    kernel.prepare_arrays(arrays, out)
}

/// The box of the recentred positions seen so far, and whether each was
/// finite.
#[derive(Clone, Copy)]
struct Bounds {
    lo: Vec3,
    hi: Vec3,
    finite: bool,
}

impl Bounds {
    const EMPTY: Self = Self {
        lo: Vec3::INFINITY,
        hi: Vec3::NEG_INFINITY,
        finite: true,
    };

    #[inline(always)]
    fn add(&mut self, r: Vec3) {
        (self.lo, self.hi) = (self.lo.min(r), self.hi.max(r));
        self.finite &= r.is_finite();
    }

    fn union(self, other: Self) -> Self {
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            finite: self.finite && other.finite,
        }
    }
}

/// Each of the three axes split at `mid` (an empty axis into two empty
/// ones).
fn split_axes<'a>(
    axes: &'a mut [&mut [f32]; 3],
    mid: usize,
) -> ([&'a mut [f32]; 3], [&'a mut [f32]; 3]) {
    let [x, y, z] = axes
        .each_mut()
        .map(|axis| axis.split_at_mut(mid.min(axis.len())));
    ([x.0, y.0, z.0], [x.1, y.1, z.1])
}

/// The three axes of `axes`, each `len` long, for every value to be
/// written: what a buffer kept from an earlier batch holds is left there
/// rather than zeroed first (a pass over the batch of its own).
fn sized(axes: &mut [Vec<f32>; 3], len: usize) -> [&mut [f32]; 3] {
    axes.each_mut().map(|axis| {
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
#[inline(always)]
fn scaled_near_one(n: DVec3) -> Vec3 {
    let largest = n.abs().max_element();
    // A normal near unit length, the usual one, by the shortest way.
    if (0.5..2.0).contains(&largest) {
        return if largest < 1.0 { n * 2.0 } else { n }.as_vec3();
    }
    scaled_far_from_one(n, largest)
}

/// [`scaled_near_one`] of `n`, whose largest component `largest` lies
/// outside [0.5, 2).
#[cold]
fn scaled_far_from_one(n: DVec3, largest: f64) -> Vec3 {
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
    use crate::kernel::positional::UNSCALED_DISTANCE2;
    use crate::{Light, LightModel, LightPosition, LightSet, Viewer};

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

    fn kernel(lights: &[DVec3], positions: &[DVec3]) -> Kernel {
        let lights = lights
            .iter()
            .map(|&p| Light {
                position: LightPosition::Positional(p),
                ..Light::default()
            })
            .collect();
        let set = LightSet::new(LightModel::default(), lights, Viewer::Infinite(DVec3::Z))
            .expect("a valid light set");
        Kernel::new(&set, positions)
    }

    /// `count` random positions in a box 20 wide and normals up to 3 long
    /// on each axis, from the generator seeded with `seed`.
    fn random_batch(seed: u64, count: usize) -> (Vec<DVec3>, Vec<DVec3>) {
        let mut rng = crate::test_rng::Rng::new(seed);
        let mut random = || DVec3::new(rng.signed(), rng.signed(), rng.signed());
        let positions = (0..count).map(|_| random() * 10.0).collect();
        let normals = (0..count).map(|_| random() * 3.0).collect();
        (positions, normals)
    }

    /// A batch prepared from arrays, by every build this CPU runs, is the
    /// batch prepared from pairs, bit for bit: normals near unit length
    /// and far from it (zero, tiny, huge, not a number, on the ends of
    /// [0.5, 2)), with and without positions, normalised and not, with a
    /// position that is not finite, and a length that fills no whole lane.
    #[test]
    fn prepared_lanes_are_the_prepared_pairs() {
        let count = 3 * BOUND_LANES + 5;
        let (mut positions, mut normals) = random_batch(0x51ed_27a0_3c6b_9e11u64, count);
        let special = [
            DVec3::ZERO,
            DVec3::new(1e-300, -2e-301, 0.0),
            DVec3::new(1e300, 3e299, -1e300),
            DVec3::new(f64::NAN, 0.7, 0.1),
            DVec3::new(0.5, -0.25, 0.1),
            DVec3::new(-2.0, 1.0, 0.5),
            DVec3::new(0.0, -1.999_999, f64::INFINITY),
        ];
        normals[..special.len()].copy_from_slice(&special);
        let axes =
            |v: &[DVec3]| [0, 1, 2].map(|axis| v.iter().map(|p| p[axis]).collect::<Vec<f64>>());
        for infinite in [false, true] {
            if infinite {
                positions[count - 3].y = f64::NEG_INFINITY;
            }
            for normalize in [false, true] {
                let model = LightModel {
                    normalize_normals: normalize,
                    ..LightModel::default()
                };
                let positional = Light {
                    position: LightPosition::Positional(DVec3::new(1.0, 2.0, 3.0)),
                    ..Light::default()
                };
                for light in [positional, Light::default()] {
                    let set = LightSet::new(model, vec![light], Viewer::Infinite(DVec3::Z))
                        .expect("a valid light set");
                    let kernel = Kernel::new(&set, &positions);
                    let mut pairs = Vertices::default();
                    let both = positions.iter().copied().zip(normals.iter().copied());
                    kernel.prepare_into(both, &mut pairs);
                    let (p, n) = (axes(&positions), axes(&normals));
                    for isa in InstructionSet::here() {
                        let mut lanes = Vertices::default();
                        let (p, n) = (
                            p.each_ref().map(Vec::as_slice),
                            n.each_ref().map(Vec::as_slice),
                        );
                        kernel.prepare_lanes_on(isa, p, n, &mut lanes);
                        let context = format!("{isa}, normalised {normalize}, infinite {infinite}");
                        let bits = |axes: &[Vec<f32>; 3]| {
                            axes.each_ref()
                                .map(|a| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                        };
                        assert_eq!(bits(&lanes.normals), bits(&pairs.normals), "{context}");
                        assert_eq!(bits(&lanes.positions), bits(&pairs.positions), "{context}");
                        assert_eq!(lanes.bounds, pairs.bounds, "{context}");
                        assert_eq!(lanes.len, count, "{context}");
                        assert!(kernel.prepared(&lanes), "{context}");
                    }
                }
            }
        }
    }

    /// A batch converted in halves on the pool is the batch converted in
    /// one piece, value for value, with the same bounds: with and without
    /// positions, and with a position that is not finite.
    #[test]
    fn prepare_in_halves_is_prepare_in_one_piece() {
        let count = 3 * TASK_VERTICES + 7;
        let (mut positions, normals) = random_batch(0x9e37_79b9_7f4a_7c15u64, count);
        let directional = LightSet::new(
            LightModel::default(),
            vec![Light::default()],
            Viewer::Infinite(DVec3::Z),
        )
        .expect("a valid light set");
        let kernels = [
            kernel(&[DVec3::new(1.0, 2.0, 3.0)], &positions),
            Kernel::new(&directional, &positions),
        ];
        for infinite in [false, true] {
            if infinite {
                positions[count - 5].x = f64::INFINITY;
            }
            for kernel in &kernels {
                let halves = kernel.prepare(&positions, &normals);
                let mut one_piece = Vertices::default();
                let pairs = positions.iter().copied().zip(normals.iter().copied());
                kernel.prepare_into(pairs, &mut one_piece);
                assert_eq!(halves.positions, one_piece.positions);
                assert_eq!(halves.normals, one_piece.normals);
                assert_eq!(halves.bounds, one_piece.bounds);
                assert_eq!(halves.len, count);
                assert_eq!(
                    halves.bounds.is_some(),
                    kernel.depends_on_position && !infinite
                );
                assert!(kernel.prepared(&halves));
            }
        }
    }

    /// A light said to be in range is, for every vertex, by the f32 `|d|²`
    /// the lanes compute; lights 1e-16 and 1e16 from a vertex are not, one
    /// outside the box at a few times its size is; a non-finite position
    /// leaves every light to the lanes' own tests.
    #[test]
    fn lights_in_range_bound_every_lane() {
        let mut rng = crate::test_rng::Rng::new(0x2545_f491_4f6c_dd1du64);
        let mut random = || rng.signed();
        for round in 0..100 {
            let scale = 10f64.powi(round % 7 * 3 - 9);
            let positions: Vec<DVec3> = (0..50)
                .map(|_| DVec3::new(random(), random(), random()) * scale)
                .collect();
            let normals = vec![DVec3::Z; positions.len()];
            let lights = [
                DVec3::new(random(), random(), random()) * scale * 3.0,
                positions[0] + DVec3::new(1e-16, 0.0, 0.0),
                positions[0] + DVec3::new(0.0, 1e16, 0.0),
                // Outside the box, at an ordinary distance from it.
                DVec3::new(5.0 * scale, 0.0, 0.0),
            ];
            let kernel = kernel(&lights, &positions);
            let vertices = kernel.prepare(&positions, &normals);
            let mask = kernel.lights_in_range(&vertices);
            assert_eq!(mask & 0b110, 0, "round {round}: {mask:b}");
            for (i, source) in kernel.sources.iter().enumerate() {
                let super::super::Source::Positional { p_pli, .. } = source else {
                    panic!("a light at a point")
                };
                if mask >> i & 1 == 1 {
                    for v in 0..vertices.len {
                        let d = [0, 1, 2].map(|axis| p_pli[axis] - vertices.positions[axis][v]);
                        let d2 = d[2].mul_add(d[2], d[1].mul_add(d[1], d[0] * d[0]));
                        assert!(UNSCALED_DISTANCE2.contains(&d2), "round {round}: {d2:e}");
                    }
                }
            }
            assert_eq!(mask & 0b1000, 0b1000, "round {round}: {mask:b}");
        }
        let mut positions = vec![DVec3::ONE; 20];
        let normals = vec![DVec3::Z; 20];
        let kernel = kernel(&[DVec3::new(5.0, 0.0, 0.0)], &positions);
        assert_eq!(
            kernel.lights_in_range(&kernel.prepare(&positions, &normals)),
            1
        );
        positions[7].y = f64::INFINITY;
        let vertices = kernel.prepare(&positions, &normals);
        assert_eq!(kernel.lights_in_range(&vertices), 0);
    }
}
