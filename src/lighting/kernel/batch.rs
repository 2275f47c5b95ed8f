//! The batch evaluator of the f32 tiers: vertices in blocks of [`BLOCK`],
//! held as structure of arrays, with the light loop outside and the vertex
//! loop inside so that the compiler vectorises the vertex loop (8 lanes where
//! the CPU has AVX2, chosen at run time; 4 otherwise).
//!
//! Like Mesa's fixed-function pipeline, which builds its vertex program from
//! a key of the enabled state, the evaluator is specialised once per scene:
//! its [`StateKey`] (local viewer, specular, Phong) picks a monomorphised
//! block function, and each light picks its own loop (directional, positional
//! with or without attenuation, spot), so no vertex loop branches on a scene
//! feature. A scene with one directional light and no specular runs one
//! multiply-add loop per colour channel, and never reads the positions.
//!
//! The documented error bounds hold where the equation is continuous. It
//! has two steps: the edge of a spot cone and, with shininess 0, `f_i` at
//! `n·VP = 0`. A vertex within about 1e-7 (the f32 rounding of its
//! direction) of a step can land on the other side of it than the f64
//! reference puts it; both tiers compute `VP_pli` and the cone test to full
//! f32 accuracy so that this stays that rare.

// The vertex loops index several arrays of one block by lane on purpose:
// that is the structure of arrays the vectoriser needs.
#![allow(clippy::needless_range_loop)]

use std::mem::MaybeUninit;

use glam::{DVec3, Vec3, Vec4};
use rayon::prelude::*;

use super::{Kernel, SideProducts, Source, Viewer32};
use crate::lighting::fastmath::{Accurate, Fast, Math, cosine};
use crate::lighting::{ColorControl, MAX_ATTENUATION, SpecularModel};

/// Vertices per block: the working set stays in L1.
const BLOCK: usize = 64;

/// Blocks per rayon task.
const BLOCKS_PER_TASK: usize = 64;

/// How the f32 tiers compute `pow` and `1/√x`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tier {
    Accurate,
    Fast,
}

/// The features of a scene that change the shape of the vertex loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StateKey {
    pub local_viewer: bool,
    /// Some light has a non-zero specular product on some side.
    pub specular: bool,
    pub phong: bool,
    /// Normals used as given (GL_NORMALIZE off): the specular base is then
    /// not a cosine.
    pub raw_normals: bool,
}

impl Kernel {
    /// The state key of this scene.
    pub fn state_key(&self) -> StateKey {
        let sides = std::iter::once(&self.front).chain(self.back.as_ref());
        StateKey {
            local_viewer: matches!(self.viewer, Viewer32::Local(_)),
            specular: sides
                .flat_map(|s| s.products.iter())
                .any(|[_, _, specular]| *specular != Vec3::ZERO),
            phong: self.specular_model == SpecularModel::Phong,
            raw_normals: !self.normalize,
        }
    }

    /// Lights every vertex with the evaluator of `tier`, in parallel on the
    /// current rayon pool.
    pub fn shade(&self, tier: Tier, positions: &[DVec3], normals: &[DVec3]) -> super::Colors {
        assert_eq!(positions.len(), normals.len());
        let run = block_function(tier, self.state_key());
        let len = positions.len();
        // Written once, by the tasks: no zero-filling pass over memory that
        // is slow to touch the first time.
        let mut front = Vec::<Vec4>::with_capacity(len);
        let mut back = self.back.as_ref().map(|_| Vec::<Vec4>::with_capacity(len));
        let task = BLOCK * BLOCKS_PER_TASK;
        let inputs = positions.par_chunks(task).zip(normals.par_chunks(task));
        let front_out = &mut front.spare_capacity_mut()[..len];
        match &mut back {
            None => inputs
                .zip(front_out.par_chunks_mut(task))
                .for_each(|((ps, ns), f)| self.run_task(run, ps, ns, f, None)),
            Some(back) => inputs
                .zip(
                    front_out
                        .par_chunks_mut(task)
                        .zip(back.spare_capacity_mut()[..len].par_chunks_mut(task)),
                )
                .for_each(|((ps, ns), (f, b))| self.run_task(run, ps, ns, f, Some(b))),
        }
        // SAFETY: the chunks above cover 0..len, and `run_task` writes every
        // element of its chunk (`Block::store` on each block of it).
        unsafe {
            front.set_len(len);
            if let Some(back) = &mut back {
                back.set_len(len);
            }
        }
        super::Colors { front, back }
    }

    fn run_task(
        &self,
        run: BlockFn,
        positions: &[DVec3],
        normals: &[DVec3],
        front: &mut [MaybeUninit<Vec4>],
        mut back: Option<&mut [MaybeUninit<Vec4>]>,
    ) {
        let mut block = Block::default();
        for (start, (ps, ns)) in positions
            .chunks(BLOCK)
            .zip(normals.chunks(BLOCK))
            .enumerate()
            .map(|(i, c)| (i * BLOCK, c))
        {
            block.load(self, ps, ns);
            let end = start + ps.len();
            run(self, &mut block, &self.front);
            block.store(self, &self.front, &mut front[start..end]);
            if let (Some(products), Some(out)) = (&self.back, back.as_deref_mut()) {
                block.negate_normals();
                run(self, &mut block, products);
                block.store(self, products, &mut out[start..end]);
            }
        }
    }
}

/// One block of vertices, structure of arrays.
struct Block {
    /// Recentred positions.
    p: [[f32; BLOCK]; 3],
    /// Normals as the lighting sees them (normalised if asked).
    n: [[f32; BLOCK]; 3],
    /// `VP_e`, for a local viewer.
    e: [[f32; BLOCK]; 3],
    primary: [[f32; BLOCK]; 3],
    secondary: [[f32; BLOCK]; 3],
}

impl Default for Block {
    fn default() -> Self {
        let zero = [[0.0; BLOCK]; 3];
        Self {
            p: zero,
            n: zero,
            e: zero,
            primary: zero,
            secondary: zero,
        }
    }
}

impl Block {
    /// Loads up to [`BLOCK`] vertices; the lanes past the end are zero.
    fn load(&mut self, kernel: &Kernel, positions: &[DVec3], normals: &[DVec3]) {
        if positions.len() < BLOCK {
            self.p = [[0.0; BLOCK]; 3];
            self.n = [[0.0; BLOCK]; 3];
        }
        if kernel.depends_on_position {
            for (i, &p) in positions.iter().enumerate() {
                let p = (p - kernel.centre).as_vec3();
                for axis in 0..3 {
                    self.p[axis][i] = p[axis];
                }
            }
        }
        for (i, &n) in normals.iter().enumerate() {
            let n = if kernel.normalize {
                within_f32_range(n)
            } else {
                n.as_vec3()
            };
            for axis in 0..3 {
                self.n[axis][i] = n[axis];
            }
        }
        if kernel.normalize {
            for i in 0..BLOCK {
                let (unit, _) =
                    unit_and_length::<Accurate>([self.n[0][i], self.n[1][i], self.n[2][i]]);
                for axis in 0..3 {
                    self.n[axis][i] = unit[axis];
                }
            }
        }
        if let Viewer32::Local(eye) = kernel.viewer {
            for i in 0..BLOCK {
                let d = [
                    eye.x - self.p[0][i],
                    eye.y - self.p[1][i],
                    eye.z - self.p[2][i],
                ];
                let (unit, _) = unit_and_length::<Accurate>(d);
                for axis in 0..3 {
                    self.e[axis][i] = unit[axis];
                }
            }
        }
    }

    fn negate_normals(&mut self) {
        for axis in &mut self.n {
            for v in axis.iter_mut() {
                *v = -*v;
            }
        }
    }

    /// Writes the clamped colours of the first `out.len()` lanes.
    fn store(&self, kernel: &Kernel, side: &SideProducts, out: &mut [MaybeUninit<Vec4>]) {
        for (i, o) in out.iter_mut().enumerate() {
            let primary = Vec3::new(self.primary[0][i], self.primary[1][i], self.primary[2][i]);
            let secondary = Vec3::new(
                self.secondary[0][i],
                self.secondary[1][i],
                self.secondary[2][i],
            );
            let rgb = match kernel.color_control {
                ColorControl::Single => primary + secondary,
                ColorControl::SeparateSpecular => {
                    primary.clamp(Vec3::ZERO, Vec3::ONE) + secondary.clamp(Vec3::ZERO, Vec3::ONE)
                }
            };
            o.write(rgb.clamp(Vec3::ZERO, Vec3::ONE).extend(side.alpha));
        }
    }
}

/// Lights one side of a loaded block.
type BlockFn = fn(&Kernel, &mut Block, &SideProducts);

/// The block function for a tier and a state key, compiled for AVX2 and FMA
/// where the CPU has them.
fn block_function(tier: Tier, key: StateKey) -> BlockFn {
    match tier {
        Tier::Accurate => block_function_for::<Accurate>(key),
        Tier::Fast => block_function_for::<Fast>(key),
    }
}

fn block_function_for<M: Math>(key: StateKey) -> BlockFn {
    macro_rules! pick {
        ($($local:literal $spec:literal $phong:literal $raw:literal),*) => {
            match (key.local_viewer, key.specular, key.phong, key.raw_normals) {
                $(($local, $spec, $phong, $raw) => dispatch::<M, $local, $spec, $phong, $raw>(),)*
            }
        };
    }
    pick!(
        false false false false, false false false true, false false true false,
        false false true true, false true false false, false true false true,
        false true true false, false true true true, true false false false,
        true false false true, true false true false, true false true true,
        true true false false, true true false true, true true true false,
        true true true true
    )
}

/// Chooses the AVX2 build of a block function at run time.
fn dispatch<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>()
-> BlockFn {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
        return |k, b, s| {
            // SAFETY: the CPU has AVX2 and FMA, checked just above.
            unsafe { light_block_avx2::<M, LOCAL, SPEC, PHONG, RAW>(k, b, s) }
        };
    }
    light_block::<M, LOCAL, SPEC, PHONG, RAW>
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn light_block_avx2<
    M: Math,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
>(
    kernel: &Kernel,
    block: &mut Block,
    side: &SideProducts,
) {
    light_block::<M, LOCAL, SPEC, PHONG, RAW>(kernel, block, side)
}

/// Section 2.14.1 for one side of a block: the light loop outside, the
/// vertex loops inside.
#[inline(always)]
fn light_block<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>(
    kernel: &Kernel,
    block: &mut Block,
    side: &SideProducts,
) {
    for axis in 0..3 {
        block.primary[axis] = [side.base[axis]; BLOCK];
        block.secondary[axis] = [0.0; BLOCK];
    }
    let infinite_eye = match kernel.viewer {
        Viewer32::Infinite(dir) => dir,
        Viewer32::Local(_) => Vec3::ZERO,
    };
    for (source, products) in kernel.sources.iter().zip(&side.products) {
        let light = LightColors::new(products, side.shininess);
        match *source {
            Source::Directional { vp_pli, spot } => {
                let h = super::unit_or_zero32(vp_pli + infinite_eye).0;
                directional::<M, LOCAL, SPEC, PHONG, RAW>(
                    block,
                    &light,
                    vp_pli,
                    h,
                    infinite_eye,
                    spot,
                )
            }
            Source::Positional { p_pli, k, cone } => {
                let at = Positional {
                    p_pli,
                    k,
                    clamp: kernel.attenuation_clamp,
                    eye: infinite_eye,
                    cone,
                };
                match (k == [1.0, 0.0, 0.0], cone.is_some()) {
                    (true, false) => {
                        positional::<M, LOCAL, SPEC, PHONG, RAW, false, false>(block, &light, &at)
                    }
                    (false, false) => {
                        positional::<M, LOCAL, SPEC, PHONG, RAW, true, false>(block, &light, &at)
                    }
                    (true, true) => {
                        positional::<M, LOCAL, SPEC, PHONG, RAW, false, true>(block, &light, &at)
                    }
                    (false, true) => {
                        positional::<M, LOCAL, SPEC, PHONG, RAW, true, true>(block, &light, &at)
                    }
                }
            }
        }
    }
}

/// One light's colour products on one side.
struct LightColors {
    ambient: Vec3,
    diffuse: Vec3,
    specular: Vec3,
    shininess: f32,
}

impl LightColors {
    fn new([ambient, diffuse, specular]: &[Vec3; 3], shininess: f32) -> Self {
        Self {
            ambient: *ambient,
            diffuse: *diffuse,
            specular: *specular,
            shininess,
        }
    }
}

/// A positional light, recentred.
struct Positional {
    p_pli: Vec3,
    k: [f32; 3],
    clamp: bool,
    /// The infinite viewer's direction (unused for a local viewer).
    eye: Vec3,
    cone: Option<super::Cone>,
}

/// A light at infinity: `VP_pli`, the infinite viewer's `ĥ` and the spot
/// factor are the same for every vertex.
#[inline(always)]
fn directional<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>(
    b: &mut Block,
    light: &LightColors,
    vp: Vec3,
    h_infinite: Vec3,
    eye: Vec3,
    spot: f32,
) {
    let ambient = light.ambient * spot;
    let diffuse = light.diffuse * spot;
    let specular = light.specular * spot;
    for i in 0..BLOCK {
        let n = [b.n[0][i], b.n[1][i], b.n[2][i]];
        let n_dot_vp = n[0] * vp.x + n[1] * vp.y + n[2] * vp.z;
        let lit = n_dot_vp.max(0.0);
        for c in 0..3 {
            b.primary[c][i] += ambient[c] + lit * diffuse[c];
        }
        if SPEC {
            let e = [b.e[0][i], b.e[1][i], b.e[2][i]];
            let power = specular_power::<M, LOCAL, PHONG, RAW>(
                n,
                n_dot_vp,
                vp.to_array(),
                e,
                h_infinite,
                eye,
                light.shininess,
            );
            let f = if n_dot_vp > 0.0 { power } else { 0.0 };
            for c in 0..3 {
                b.secondary[c][i] += f * specular[c];
            }
        }
    }
}

/// A light at a point: `VP_pli`, the distance, attenuation and spot per
/// vertex. `ATT`: the coefficients are not (1, 0, 0); `SPOT`: a cone.
#[inline(always)]
fn positional<
    M: Math,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
    const ATT: bool,
    const SPOT: bool,
>(
    b: &mut Block,
    light: &LightColors,
    at: &Positional,
) {
    let [k0, k1, k2] = at.k;
    let cone = at.cone.unwrap_or(super::Cone {
        direction: Vec3::ZERO,
        exponent: 0.0,
        cos_cutoff: 0.0,
        one_minus_cos_cutoff: 0.0,
    });
    for i in 0..BLOCK {
        let d = [
            at.p_pli.x - b.p[0][i],
            at.p_pli.y - b.p[1][i],
            at.p_pli.z - b.p[2][i],
        ];
        // `VP_pli` to full f32 accuracy in every tier: the cone test is a
        // step, and an approximate direction would move its edge.
        let (vp, distance) = unit_and_length::<Accurate>(d);
        let mut scale = 1.0;
        if ATT {
            let att =
                (1.0 / (k0 + k1 * distance + k2 * distance * distance)).min(MAX_ATTENUATION as f32);
            scale = if at.clamp { att.min(1.0) } else { att };
        }
        if SPOT {
            // `P_pli V ⊙ ŝ ≥ cos(cutoff)`, tested on `1 − cos` so that a
            // cutoff of 0 still lights its axis; the clamp of `⊙` puts every
            // vertex behind the light on the edge of a 90° cone.
            let c = cosine([-vp[0], -vp[1], -vp[2]], cone.direction.to_array());
            let inside = if c.positive {
                c.one_minus <= cone.one_minus_cos_cutoff
            } else {
                cone.cos_cutoff <= 0.0
            };
            let power = M::pow_cosine(c, cone.exponent);
            scale *= if inside { power } else { 0.0 };
        }
        let n = [b.n[0][i], b.n[1][i], b.n[2][i]];
        let n_dot_vp = n[0] * vp[0] + n[1] * vp[1] + n[2] * vp[2];
        let lit = n_dot_vp.max(0.0);
        for c in 0..3 {
            b.primary[c][i] += scale * (light.ambient[c] + lit * light.diffuse[c]);
        }
        if SPEC {
            let e = [b.e[0][i], b.e[1][i], b.e[2][i]];
            // ĥ of the infinite viewer, not normalised: `specular_power`
            // normalises it only where it needs to.
            let h_infinite = Vec3::new(vp[0] + at.eye.x, vp[1] + at.eye.y, vp[2] + at.eye.z);
            let power = specular_power::<M, LOCAL, PHONG, RAW>(
                n,
                n_dot_vp,
                vp,
                e,
                h_infinite,
                at.eye,
                light.shininess,
            );
            let f = if n_dot_vp > 0.0 { scale * power } else { 0.0 };
            for c in 0..3 {
                b.secondary[c][i] += f * light.specular[c];
            }
        }
    }
}

/// The specular factor `(n⊙ĥ)^s` (Blinn-Phong) or `(r⊙VP_e)^s` (Phong). For
/// an infinite viewer `VP_e` is `eye` and `ĥ` (the halfway vector, not
/// necessarily normalised) comes in as `h_infinite`. With unit normals the
/// base is a cosine and [`Math::pow_cos`] evaluates it without losing the
/// digits near 1; raw normals take the plain power of the dot product.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn specular_power<M: Math, const LOCAL: bool, const PHONG: bool, const RAW: bool>(
    n: [f32; 3],
    n_dot_vp: f32,
    vp: [f32; 3],
    e: [f32; 3],
    h_infinite: Vec3,
    eye: Vec3,
    shininess: f32,
) -> f32 {
    let vp_e = if LOCAL { e } else { eye.to_array() };
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    if PHONG {
        let r = [
            2.0 * n_dot_vp * n[0] - vp[0],
            2.0 * n_dot_vp * n[1] - vp[1],
            2.0 * n_dot_vp * n[2] - vp[2],
        ];
        if RAW {
            M::pow(dot(r, vp_e), shininess)
        } else {
            M::pow_cos(r, vp_e, shininess)
        }
    } else {
        let h = if LOCAL {
            [vp[0] + e[0], vp[1] + e[1], vp[2] + e[2]]
        } else {
            h_infinite.to_array()
        };
        if RAW {
            M::pow(dot(n, unit_and_length::<M>(h).0), shininess)
        } else {
            M::pow_cos(n, h, shininess)
        }
    }
}

/// A normal that is about to be normalised, as f32 in the same direction: a
/// length beyond f32's range is first scaled by a power of two, exactly.
#[inline(always)]
fn within_f32_range(n: DVec3) -> Vec3 {
    let largest = n.abs().max_element();
    if (1e-30..=1e30).contains(&largest) || largest == 0.0 {
        n.as_vec3()
    } else {
        (n * 2f64.powi(-largest.log2().floor() as i32)).as_vec3()
    }
}

/// The unit vector along `v` and its length; zero for a zero vector. `v` is
/// first scaled by the power of two that brings its largest component into
/// [1, 2), so that its squared length neither overflows nor underflows f32 (a
/// light 1e20 or 1e-30 away); the scaling is exact.
#[inline(always)]
fn unit_and_length<M: Math>(v: [f32; 3]) -> ([f32; 3], f32) {
    let largest = v[0].abs().max(v[1].abs()).max(v[2].abs());
    let exponent = (largest.to_bits() >> 23).min(253);
    let scale = f32::from_bits((254 - exponent) << 23); // 2^(127 − exponent)
    let w = [v[0] * scale, v[1] * scale, v[2] * scale];
    let len2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    let inv = M::rsqrt(len2.max(f32::MIN_POSITIVE));
    let inv = if len2 > 0.0 { inv } else { 0.0 };
    let len = len2 * inv / scale;
    ([w[0] * inv, w[1] * inv, w[2] * inv], len)
}
