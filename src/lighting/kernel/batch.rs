//! The batch evaluator of the f32 tiers: vertices in blocks of [`BLOCK`],
//! held as structure of arrays, with the light loop outside and the vertex
//! loop inside so that the compiler vectorises the vertex loop: 16 lanes
//! where the CPU has AVX-512, 8 with AVX2 and FMA, chosen at run time. A CPU
//! without FMA gets the baseline build, correct but slow: each `mul_add` of
//! the polynomials is a library call there. The whole task (load, light,
//! store) is built for the chosen instruction set, and it reads f32 inputs
//! [`Kernel::prepare`]d once per batch: 12 bytes of normal and, where
//! lighting needs it, 12 of position. The square roots and divisions of a
//! block are passes of their own, so that AVX-512 can take them from its
//! estimates (see [`super::isa`]), and whole powers of a cosine are
//! multiplications (see [`Power`]).
//!
//! Like Mesa's fixed-function pipeline, which builds its vertex program from
//! a key of the enabled state, the evaluator is specialised once per scene:
//! its [`StateKey`] (local viewer, specular, Phong, raw normals) picks a
//! monomorphised task function, and each light picks its own loop (directional, positional
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

#[cfg(target_arch = "x86_64")]
use super::isa::Avx512;
use super::isa::{Isa, Plain};
use super::{Kernel, SideProducts, Source, Viewer32};
use crate::lighting::fastmath::{
    Accurate, Cosine, Fast, Math, Power, cos2_of_unit, cosine, cosine_of_unit, whole_base,
};
use crate::lighting::{ColorControl, MAX_ATTENUATION, SpecularModel};

/// Vertices per block: the working set stays in L1.
pub(super) const BLOCK: usize = 64;

/// Vertices per rayon task: 64 blocks. A batch of one task runs on the
/// calling thread.
const TASK: usize = BLOCK * 64;

/// How the f32 tiers compute `pow`, whole powers and `1/x`.
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

    /// The specular terms are summed and clamped on their own (else they go
    /// into the primary colour).
    fn separate_specular(&self) -> bool {
        self.color_control == ColorControl::SeparateSpecular
    }

    /// Converts a batch into the f32 form [`Kernel::shade`] reads: positions
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

    /// Lights every vertex with the evaluator of `tier`, in parallel on the
    /// current rayon pool.
    pub fn shade(&self, tier: Tier, vertices: &Vertices) -> super::Colors {
        let mut colors = super::Colors::default();
        self.shade_into(tier, vertices, &mut colors);
        colors
    }

    /// [`Kernel::shade`] into the buffers of `out`, which keep their memory
    /// from one call to the next: memory touched for the first time is slow
    /// to write.
    pub fn shade_into(&self, tier: Tier, vertices: &Vertices, out: &mut super::Colors) {
        assert!(
            vertices.centre == self.centre
                && vertices.normalized == self.normalize
                && (vertices.positions[0].len() == vertices.len || !self.depends_on_position),
            "vertices prepared by another kernel"
        );
        let run = task_function(tier, self.state_key());
        let len = vertices.len;
        let front = &mut out.front;
        front.clear();
        front.reserve(len);
        if self.back.is_some() {
            out.back.get_or_insert_with(Vec::new).clear();
        } else {
            out.back = None;
        }
        let back = out.back.as_mut().map(|back| {
            back.reserve(len);
            &mut back.spare_capacity_mut()[..len]
        });
        let front_out = &mut front.spare_capacity_mut()[..len];
        if len <= TASK {
            // One task runs where it is called, without a hop to the pool.
            run(self, vertices, 0, front_out, back);
        } else {
            self.run_tasks(run, vertices, front_out, back);
        }
        // SAFETY: the tasks cover 0..len, and each task function writes
        // every element of its chunks (`Block::store` on each block of it).
        unsafe {
            front.set_len(len);
            if let Some(back) = &mut out.back {
                back.set_len(len);
            }
        }
    }

    /// Runs the task function on chunks of the batch in parallel.
    fn run_tasks(
        &self,
        run: TaskFn,
        vertices: &Vertices,
        front: &mut [MaybeUninit<Vec4>],
        back: Option<&mut [MaybeUninit<Vec4>]>,
    ) {
        let front_out = front.par_chunks_mut(TASK);
        match back {
            None => front_out
                .enumerate()
                .for_each(|(i, f)| run(self, vertices, i * TASK, f, None)),
            Some(back) => front_out
                .zip(back.par_chunks_mut(TASK))
                .enumerate()
                .for_each(|(i, (f, b))| run(self, vertices, i * TASK, f, Some(b))),
        }
    }
}

/// A batch of vertices in the form the f32 tiers read, made by
/// [`Kernel::prepare`]: 12 bytes of normal per vertex, and 12 of position
/// when the lighting uses positions.
#[derive(Clone, Debug, Default)]
pub struct Vertices {
    /// What the preparing kernel did, checked by the kernel that shades.
    centre: DVec3,
    normalized: bool,
    len: usize,
    /// Recentred; empty when the lighting does not depend on position.
    positions: [Vec<f32>; 3],
    normals: [Vec<f32>; 3],
    /// Per vertex, bit `i`: light `i` reaches it. None: every light does.
    visible: Option<Vec<u64>>,
}

impl Vertices {
    /// Says which lights reach each vertex (bit `i` of its mask for light
    /// `i`); a light that does not adds only its ambient term, as a light
    /// whose shadow ray is blocked.
    pub fn set_visibility(&mut self, masks: Vec<u64>) {
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

/// Lights the vertices from `start` on into `front` (and `back`), one block
/// at a time.
type TaskFn =
    fn(&Kernel, &Vertices, usize, &mut [MaybeUninit<Vec4>], Option<&mut [MaybeUninit<Vec4>]>);

#[inline(always)]
fn run_task<
    M: Math,
    I: Isa,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
>(
    kernel: &Kernel,
    vertices: &Vertices,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    mut back: Option<&mut [MaybeUninit<Vec4>]>,
) {
    let mut block = SPARE_BLOCK.take().unwrap_or_default();
    // A batch of one task is small and was just written by its caller.
    let prefetch = vertices.len > TASK;
    for offset in (0..front.len()).step_by(BLOCK) {
        let end = (offset + BLOCK).min(front.len());
        let next = offset + PREFETCH_AHEAD * BLOCK;
        if prefetch && next + BLOCK <= front.len() {
            let back = back.as_deref().map(|b| &b[next..]);
            prefetch_block(kernel, vertices, start + next, &front[next..], back);
        }
        block.load::<M, I, LOCAL, PHONG, RAW>(kernel, vertices, start + offset..start + end);
        light_side::<M, I, LOCAL, SPEC, PHONG, RAW>(kernel, &mut block, &kernel.front);
        block.store(kernel, &kernel.front, &mut front[offset..end]);
        if let (Some(products), Some(out)) = (&kernel.back, back.as_deref_mut()) {
            block.negate_normals();
            light_side::<M, I, LOCAL, SPEC, PHONG, RAW>(kernel, &mut block, products);
            block.store(kernel, products, &mut out[offset..end]);
        }
    }
    SPARE_BLOCK.set(Some(block));
}

/// How many blocks ahead a task asks for its inputs and outputs. A block's
/// passes are too long for the CPU to look past them to the next block's
/// loads, so without prefetching each block waits for memory in turn. Two
/// blocks ahead, the 1-directional batch of 1e6 vertices ran 30–45% faster
/// on one core; four was no better.
const PREFETCH_AHEAD: usize = 2;

/// Asks for the cache lines of the whole block of vertices from `at` and of
/// its colours (the first [`BLOCK`] of `front` and `back`) ahead of their
/// use: a fixed count of prefetches, unrolled.
#[inline(always)]
fn prefetch_block(
    kernel: &Kernel,
    vertices: &Vertices,
    at: usize,
    front: &[MaybeUninit<Vec4>],
    back: Option<&[MaybeUninit<Vec4>]>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let positions: &[Vec<f32>] = if kernel.depends_on_position {
            &vertices.positions
        } else {
            &[]
        };
        for axis in vertices.normals.iter().chain(positions) {
            let block = &axis[at..at + BLOCK];
            for line in 0..BLOCK / 16 {
                // SAFETY: the address is within `block`; a prefetch reads
                // nothing, and SSE is part of every x86-64 CPU.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(block.as_ptr().add(16 * line).cast()) }
            }
        }
        for colors in std::iter::once(front).chain(back) {
            let block = &colors[..BLOCK];
            for line in 0..BLOCK / 4 {
                // SAFETY: as above.
                unsafe { _mm_prefetch::<_MM_HINT_T0>(block.as_ptr().add(4 * line).cast()) }
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (kernel, vertices, at, front, back);
}

thread_local! {
    /// Each thread's block between two tasks. A block is 8 KB, and zeroing
    /// a new one costs as much as lighting a render tile's 256 vertices.
    /// What the last task left in it is overwritten as within a task, where
    /// one block serves every 64 vertices in turn.
    static SPARE_BLOCK: std::cell::Cell<Option<Box<Block>>> = const { std::cell::Cell::new(None) };
}

/// One block of vertices, structure of arrays. Every array starts on a
/// cache line (each is a multiple of 64 bytes, the masks come last), so
/// that no 64-byte vector load or store of a pass is split across two.
#[repr(C, align(64))]
struct Block {
    /// Recentred positions.
    p: [[f32; BLOCK]; 3],
    /// Normals as the lighting sees them (normalised if asked).
    n: [[f32; BLOCK]; 3],
    /// `VP_e`, for a local viewer.
    e: [[f32; BLOCK]; 3],
    primary: [[f32; BLOCK]; 3],
    /// The specular terms, where they are clamped on their own (else they
    /// go to `primary`, and this is not read).
    secondary: [[f32; BLOCK]; 3],
    /// Per light, between the loops of [`positional`]: `VP_pli` and
    /// attenuation times spot.
    vp: [[f32; BLOCK]; 3],
    scale: [f32; BLOCK],
    /// A cosine per vertex (`cos²` negative where `cos ≤ 0`), raised by
    /// [`power_block`] into `power`.
    sin2: [f32; BLOCK],
    cos2: [f32; BLOCK],
    power: [f32; BLOCK],
    /// What multiplies the specular power: visibility, `f_i`, attenuation
    /// and spot.
    gate: [f32; BLOCK],
    /// The argument and result of an [`Isa`] pass: a squared length and
    /// its `1/√`, or a denominator and its reciprocal.
    len2: [f32; BLOCK],
    inverse: [f32; BLOCK],
    /// Per light, the distances' factor 2^(exponent − 127) of
    /// [`range_scaled`].
    unscale: [f32; BLOCK],
    /// Per light: 1 where the light reaches the vertex, else 0.
    visible: [f32; BLOCK],
    /// The vertices' visibility masks, if they have them.
    masks: Option<[u64; BLOCK]>,
}

// The arrays above are whole cache lines.
const _: () = assert!((BLOCK * 4).is_multiple_of(64));

impl Default for Block {
    fn default() -> Self {
        let zero = [[0.0; BLOCK]; 3];
        Self {
            p: zero,
            n: zero,
            e: zero,
            primary: zero,
            secondary: zero,
            vp: zero,
            scale: [0.0; BLOCK],
            sin2: [0.0; BLOCK],
            cos2: [0.0; BLOCK],
            power: [0.0; BLOCK],
            gate: [0.0; BLOCK],
            len2: [0.0; BLOCK],
            inverse: [0.0; BLOCK],
            unscale: [0.0; BLOCK],
            masks: None,
            visible: [1.0; BLOCK],
        }
    }
}

impl Block {
    /// Loads the vertices of `range` (at most [`BLOCK`]); the lanes past its
    /// end are zero.
    #[inline(always)]
    fn load<M: Math, I: Isa, const LOCAL: bool, const PHONG: bool, const RAW: bool>(
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
        // A block may come from a batch with other masks (see `SPARE_BLOCK`).
        match &vertices.visible {
            Some(visible) => {
                let mut masks = [u64::MAX; BLOCK];
                masks[..count].copy_from_slice(&visible[range.clone()]);
                self.masks = Some(masks);
            }
            // `visible` is all ones but where a block with masks wrote it.
            None => {
                if self.masks.take().is_some() {
                    self.visible = [1.0; BLOCK];
                }
            }
        }
        if !RAW {
            // Normals were scaled near 1 by `Kernel::prepare`: no range
            // checks. Unit to an ULP or two in every tier, once per vertex,
            // so that the fast tier's cosines of whole powers need no
            // correction for their length once per light.
            for i in 0..BLOCK {
                let n = [self.n[0][i], self.n[1][i], self.n[2][i]];
                self.len2[i] = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).max(f32::MIN_POSITIVE);
            }
            I::rsqrt(&self.len2, &mut self.inverse);
            for i in 0..BLOCK {
                // Zero stays zero: its `len2` was raised to the smallest normal.
                for axis in 0..3 {
                    self.n[axis][i] *= self.inverse[i];
                }
            }
        }
        if let (true, Viewer32::Local(eye)) = (LOCAL, kernel.viewer) {
            for i in 0..BLOCK {
                let d = [
                    eye.x - self.p[0][i],
                    eye.y - self.p[1][i],
                    eye.z - self.p[2][i],
                ];
                let (w, len2, _) = range_scaled(d);
                for axis in 0..3 {
                    self.e[axis][i] = w[axis];
                }
                self.len2[i] = len2;
            }
            I::rsqrt(&self.len2, &mut self.inverse);
            for i in 0..BLOCK {
                let inverse = if self.len2[i] > f32::MIN_POSITIVE {
                    self.inverse[i]
                } else {
                    0.0
                };
                for axis in 0..3 {
                    self.e[axis][i] *= inverse;
                }
            }
        }
    }

    #[inline(always)]
    fn negate_normals(&mut self) {
        for axis in &mut self.n {
            for v in axis.iter_mut() {
                *v = -*v;
            }
        }
    }

    /// Writes the clamped colours of the first `out.len()` lanes,
    /// interleaved with alpha: one loop that vectorises, after the clamp of
    /// each sum of a separate specular colour. The colours go through the
    /// cache: the response encoder or the renderer reads them next, and a
    /// batch of a million (16 MB) stays in this machine's last-level cache,
    /// where non-temporal stores measured no faster.
    #[inline(always)]
    fn store(&mut self, kernel: &Kernel, side: &SideProducts, out: &mut [MaybeUninit<Vec4>]) {
        if kernel.separate_specular() {
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
            Ok(full) => self.interleave(side.alpha, full),
            Err(_) => self.interleave(side.alpha, out),
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

/// The task function for a tier and a state key, compiled for AVX-512 or
/// AVX2 with FMA where the CPU has them.
fn task_function(tier: Tier, key: StateKey) -> TaskFn {
    match tier {
        Tier::Accurate => task_function_for::<Accurate>(key),
        Tier::Fast => task_function_for::<Fast>(key),
    }
}

fn task_function_for<M: Math>(key: StateKey) -> TaskFn {
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

/// Chooses the widest build of a task function the CPU runs.
fn dispatch<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>()
-> TaskFn {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
        {
            return |k, v, s, f, b| {
                // SAFETY: the CPU has AVX-512F, AVX2 and FMA, checked just above.
                unsafe { task_avx512::<M, LOCAL, SPEC, PHONG, RAW>(k, v, s, f, b) }
            };
        }
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            return |k, v, s, f, b| {
                // SAFETY: the CPU has AVX2 and FMA, checked just above.
                unsafe { task_avx2::<M, LOCAL, SPEC, PHONG, RAW>(k, v, s, f, b) }
            };
        }
    }
    run_task::<M, Plain, LOCAL, SPEC, PHONG, RAW>
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn task_avx512<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>(
    kernel: &Kernel,
    vertices: &Vertices,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    back: Option<&mut [MaybeUninit<Vec4>]>,
) {
    run_task::<M, Avx512, LOCAL, SPEC, PHONG, RAW>(kernel, vertices, start, front, back)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn task_avx2<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>(
    kernel: &Kernel,
    vertices: &Vertices,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    back: Option<&mut [MaybeUninit<Vec4>]>,
) {
    run_task::<M, Plain, LOCAL, SPEC, PHONG, RAW>(kernel, vertices, start, front, back)
}

/// [`light_block`] with the specular cosine the side's power needs.
#[inline(always)]
fn light_side<
    M: Math,
    I: Isa,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
>(
    kernel: &Kernel,
    block: &mut Block,
    side: &SideProducts,
) {
    let whole = matches!(M::power(&side.shininess_power), Power::Whole { .. });
    if M::WHOLE_FROM_COS2 && SPEC && !PHONG && !RAW && whole {
        light_block::<M, I, LOCAL, SPEC, PHONG, RAW, true>(kernel, block, side)
    } else {
        light_block::<M, I, LOCAL, SPEC, PHONG, RAW, false>(kernel, block, side)
    }
}

/// Section 2.14.1 for one side of a block: the light loop outside, the
/// vertex loops inside.
#[inline(always)]
fn light_block<
    M: Math,
    I: Isa,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
    const COS2: bool,
>(
    kernel: &Kernel,
    block: &mut Block,
    side: &SideProducts,
) {
    let separate = kernel.separate_specular();
    for axis in 0..3 {
        block.primary[axis] = [side.base[axis]; BLOCK];
        if separate {
            block.secondary[axis] = [0.0; BLOCK];
        }
    }
    let infinite_eye = match kernel.viewer {
        Viewer32::Infinite(dir) => dir,
        Viewer32::Local(_) => Vec3::ZERO,
    };
    for (index, (source, products)) in kernel.sources.iter().zip(&side.products).enumerate() {
        if let Some(masks) = &block.masks {
            for i in 0..BLOCK {
                block.visible[i] = ((masks[i] >> index) & 1) as f32;
            }
        }
        let light = LightColors::new::<M>(products, side, separate);
        match *source {
            Source::Directional { vp_pli, spot, half } => {
                directional::<M, LOCAL, SPEC, PHONG, RAW, COS2>(
                    block,
                    &light,
                    vp_pli,
                    half,
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
                let cos2 = cone.is_some_and(|c| M::CONE_FROM_COS2 && c.from_cos2);
                macro_rules! run {
                    ($att:literal, $spot:literal, $cone_cos2:literal) => {
                        positional::<M, I, LOCAL, SPEC, PHONG, RAW, COS2, $att, $spot, $cone_cos2>(
                            block, &light, &at,
                        )
                    };
                }
                match (k == [1.0, 0.0, 0.0], cone.is_some(), cos2) {
                    (true, false, _) => run!(false, false, false),
                    (false, false, _) => run!(true, false, false),
                    (true, true, false) => run!(false, true, false),
                    (false, true, false) => run!(true, true, false),
                    (true, true, true) => run!(false, true, true),
                    (false, true, true) => run!(true, true, true),
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
    /// The tier's plan for the power of the shininess.
    power: Power,
    /// See [`Kernel::separate_specular`].
    separate: bool,
}

impl LightColors {
    fn new<M: Math>(
        [ambient, diffuse, specular]: &[Vec3; 3],
        side: &SideProducts,
        separate: bool,
    ) -> Self {
        Self {
            ambient: *ambient,
            diffuse: *diffuse,
            specular: *specular,
            shininess: side.shininess,
            power: M::power(&side.shininess_power),
            separate,
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
fn directional<
    M: Math,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
    const COS2: bool,
>(
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
    let half = Half::new(h_infinite);
    for i in 0..BLOCK {
        let n = [b.n[0][i], b.n[1][i], b.n[2][i]];
        let n_dot_vp = n[0] * vp.x + n[1] * vp.y + n[2] * vp.z;
        let lit = n_dot_vp.max(0.0) * b.visible[i];
        for c in 0..3 {
            b.primary[c][i] = lit.mul_add(diffuse[c], b.primary[c][i] + ambient[c]);
        }
        if SPEC {
            let e = [b.e[0][i], b.e[1][i], b.e[2][i]];
            let gate = if n_dot_vp > 0.0 { b.visible[i] } else { 0.0 };
            specular_base::<M, LOCAL, PHONG, RAW, COS2, true>(
                b,
                i,
                [n, vp.to_array(), e],
                n_dot_vp,
                half,
                eye,
                light.shininess,
                gate,
            );
        }
    }
    if SPEC {
        add_specular::<M, RAW, COS2>(b, light, specular);
    }
}

/// The infinite viewer's `ĥ`, where it is the same for every vertex, and
/// `1/|ĥ|²` (zero for a zero `ĥ`).
#[derive(Clone, Copy)]
struct Half {
    h: Vec3,
    inverse_h2: f32,
}

impl Half {
    fn new(h: Vec3) -> Self {
        let h2 = h.length_squared();
        Self {
            h,
            inverse_h2: if h2 > 0.0 { 1.0 / h2 } else { 0.0 },
        }
    }
}

/// A light at a point: `VP_pli`, the distance, attenuation and spot per
/// vertex. `ATT`: the coefficients are not (1, 0, 0); `SPOT`: a cone;
/// `CONE_COS2`: tested on `cos²` alone (see [`Math::CONE_FROM_COS2`]).
#[inline(always)]
fn positional<
    M: Math,
    I: Isa,
    const LOCAL: bool,
    const SPEC: bool,
    const PHONG: bool,
    const RAW: bool,
    const COS2: bool,
    const ATT: bool,
    const SPOT: bool,
    const CONE_COS2: bool,
>(
    b: &mut Block,
    light: &LightColors,
    at: &Positional,
) {
    let [k0, k1, k2] = at.k;
    let cone = at.cone.unwrap_or(super::Cone {
        direction: Vec3::ZERO,
        inverse_direction2: 0.0,
        exponent: crate::lighting::fastmath::Powers::new(0.0),
        cos_cutoff: 0.0,
        narrow: true,
        sin2_cutoff: 0.0,
        cos2_cutoff: 0.0,
        from_cos2: false,
    });
    // `P_pli − V` and its squared length as they are, where every vertex
    // of the block is between 1e-15 and 1e15 from the light (so that the
    // squared length is a normal f32 and loses nothing); scaled into range
    // by powers of two, exactly, where one is not.
    let mut out_of_range = 0u32;
    // Its sign bit clear: some lane's `cos²` is near the cutoff's.
    let mut far = u32::MAX;
    for i in 0..BLOCK {
        let d = [
            at.p_pli.x - b.p[0][i],
            at.p_pli.y - b.p[1][i],
            at.p_pli.z - b.p[2][i],
        ];
        let len2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        for axis in 0..3 {
            b.vp[axis][i] = d[axis];
        }
        b.len2[i] = len2;
        out_of_range |= u32::from(!(len2 > 1e-30 && len2 < 1e30));
    }
    if out_of_range == 0 {
        b.unscale = [1.0; BLOCK];
    } else {
        for i in 0..BLOCK {
            let d = [b.vp[0][i], b.vp[1][i], b.vp[2][i]];
            let (w, len2, unscale) = range_scaled(d);
            for axis in 0..3 {
                b.vp[axis][i] = w[axis];
            }
            b.len2[i] = len2;
            b.unscale[i] = unscale;
        }
    }
    // `VP_pli` to full f32 accuracy in every tier: the cone test is a
    // step, and an approximate direction would move its edge.
    I::rsqrt(&b.len2, &mut b.inverse);
    // `1/(k0 + k1·d + k2·d²)` capped at `MAX_ATTENUATION` (or 1 with the
    // clamp) is the reciprocal of the denominator raised to the cap's
    // reciprocal; lowered to 1e37, its reciprocal is normal.
    let (least, most) = (
        if at.clamp {
            1.0
        } else {
            (1.0 / MAX_ATTENUATION) as f32
        },
        1e37,
    );
    for i in 0..BLOCK {
        let len2 = b.len2[i];
        let inverse = if len2 > f32::MIN_POSITIVE {
            b.inverse[i]
        } else {
            0.0
        };
        let vp = [
            b.vp[0][i] * inverse,
            b.vp[1][i] * inverse,
            b.vp[2][i] * inverse,
        ];
        for axis in 0..3 {
            b.vp[axis][i] = vp[axis];
        }
        let distance = len2 * inverse * b.unscale[i];
        if ATT {
            // A coefficient past f32's range is infinite, which keeps the
            // light as dark as the reference makes it at any distance but
            // 0, where `inf · 0` would be NaN: there only `k0` counts.
            let terms = k1 * distance + k2 * distance * distance;
            let terms = if distance > 0.0 { terms } else { 0.0 };
            b.len2[i] = (k0 + terms).clamp(least, most);
        }
        let mut scale = 1.0;
        if SPOT {
            // `P_pli V ⊙ ŝ ≥ cos(cutoff)`, tested on `sin²` or `cos²` (see
            // `Cone`); the clamp of `⊙` puts every vertex behind the light on
            // the edge of a 90° cone. `CONE_COS2` leaves `sin²` unused, and
            // so the cross product out.
            let to_vertex = [-vp[0], -vp[1], -vp[2]];
            let direction = cone.direction.to_array();
            let c = if CONE_COS2 {
                cos2_of_unit(to_vertex, direction, cone.inverse_direction2)
            } else {
                cosine_of_unit(to_vertex, direction, cone.inverse_direction2)
            };
            let inside = if !c.positive {
                cone.cos_cutoff <= 0.0
            } else if cone.narrow && !CONE_COS2 {
                c.sin2 <= cone.sin2_cutoff
            } else {
                c.cos2 >= cone.cos2_cutoff
            };
            scale = if inside { scale } else { 0.0 };
            if CONE_COS2 {
                store_cos2(b, i, c.positive, c.cos2);
                let off = c.cos2 - cone.cos2_cutoff;
                far &= (-off).mul_add(off, EDGE_BAND * EDGE_BAND).to_bits();
            } else {
                store_cosine(b, i, c);
            }
        }
        b.scale[i] = scale;
    }
    if CONE_COS2 && far >> 31 == 0 {
        exact_cone_test(b, at.p_pli, cone.direction, cone.cos_cutoff);
    }
    // A block wholly outside the cone gets nothing from this light, not even
    // ambient (the spot factor multiplies every term): the rest of the
    // light's work would add zeros. Neighbouring vertices share blocks, so
    // a cone that lights part of a mesh skips the blocks it misses.
    if SPOT && b.scale.iter().fold(0, |any, s| any | s.to_bits()) == 0 {
        return;
    }
    if ATT {
        if M::ESTIMATES {
            I::recip_estimate(&b.len2, &mut b.inverse);
        } else {
            I::recip(&b.len2, &mut b.inverse);
        }
        for i in 0..BLOCK {
            b.scale[i] *= b.inverse[i];
        }
    }
    if SPOT {
        power_block::<M, CONE_COS2>(M::power(&cone.exponent), b);
    }
    if SPEC && !PHONG && !RAW {
        // `1/|ĥ|²` for the specular cosine.
        for i in 0..BLOCK {
            let vp_e = if LOCAL {
                [b.e[0][i], b.e[1][i], b.e[2][i]]
            } else {
                at.eye.to_array()
            };
            let h = [
                b.vp[0][i] + vp_e[0],
                b.vp[1][i] + vp_e[1],
                b.vp[2][i] + vp_e[2],
            ];
            b.len2[i] = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).max(f32::MIN_POSITIVE);
        }
        I::recip(&b.len2, &mut b.inverse);
    }
    // A second loop for the rest: two short loop bodies keep their values
    // in registers where one long one spills them.
    for i in 0..BLOCK {
        let vp = [b.vp[0][i], b.vp[1][i], b.vp[2][i]];
        let scale = if SPOT {
            b.scale[i] * b.power[i]
        } else {
            b.scale[i]
        };
        let n = [b.n[0][i], b.n[1][i], b.n[2][i]];
        let n_dot_vp = n[0] * vp[0] + n[1] * vp[1] + n[2] * vp[2];
        let lit = n_dot_vp.max(0.0) * b.visible[i];
        for c in 0..3 {
            b.primary[c][i] = scale.mul_add(
                lit.mul_add(light.diffuse[c], light.ambient[c]),
                b.primary[c][i],
            );
        }
        if SPEC {
            let e = [b.e[0][i], b.e[1][i], b.e[2][i]];
            // ĥ of the infinite viewer, not normalised.
            let h_infinite = Vec3::new(vp[0] + at.eye.x, vp[1] + at.eye.y, vp[2] + at.eye.z);
            let gate = if n_dot_vp > 0.0 {
                b.visible[i] * scale
            } else {
                0.0
            };
            let inverse_h2 = b.inverse[i];
            specular_base::<M, LOCAL, PHONG, RAW, COS2, false>(
                b,
                i,
                [n, vp, e],
                n_dot_vp,
                Half {
                    h: h_infinite,
                    inverse_h2,
                },
                at.eye,
                light.shininess,
                gate,
            );
        }
    }
    if SPEC {
        add_specular::<M, RAW, COS2>(b, light, light.specular);
    }
}

/// Stores a cosine of lane `i` for [`power_block`].
#[inline(always)]
fn store_cosine(b: &mut Block, i: usize, c: Cosine) {
    b.sin2[i] = c.sin2;
    b.cos2[i] = if c.positive { c.cos2 } else { -1.0 };
}

/// Where the `cos²` of the cone test is within this of the cutoff's, the
/// test might go either way: its f32 error is below 1e-6.
const EDGE_BAND: f32 = 4e-6;

/// The cone test of every lane of a block in f64, where the f32 one is not
/// sure of a lane: exact for the f32 position of the vertex and of the
/// light, and the f32 direction, so that a cone tested on `cos²` puts its
/// edge where the reference does but for the rounding of those inputs. Sets
/// `scale` to 1 inside, 0 outside.
#[inline(always)]
fn exact_cone_test(b: &mut Block, p_pli: Vec3, direction: Vec3, cos_cutoff: f64) {
    let s = direction.as_dvec3();
    for i in 0..BLOCK {
        // `V − P_pli`: each coordinate a difference of two f32, exact in f64,
        // as are the products of the dot product.
        let w = Vec3::new(b.p[0][i], b.p[1][i], b.p[2][i]).as_dvec3() - p_pli.as_dvec3();
        let dot = w.dot(s);
        let inside = cos_cutoff <= 0.0
            || (dot > 0.0
                && dot * dot >= cos_cutoff * cos_cutoff * w.length_squared() * s.length_squared());
        b.scale[i] = if inside { 1.0 } else { 0.0 };
    }
}

/// Stores lane `i`'s `cos²` alone, for [`power_block`] with `COS2`.
#[inline(always)]
fn store_cos2(b: &mut Block, i: usize, positive: bool, cos2: f32) {
    b.cos2[i] = if positive { cos2 } else { -1.0 };
}

/// `power` of every lane's stored cosine into `b.power`: see [`Power`].
/// `COS2`: the cosines are in `cos2` alone (`sin2` is not read).
#[inline(always)]
fn power_block<M: Math, const COS2: bool>(power: Power, b: &mut Block) {
    match power {
        Power::One => b.power = [1.0; BLOCK],
        Power::General(s) => {
            for i in 0..BLOCK {
                let c = stored_cosine::<COS2>(b, i);
                let c = Cosine {
                    cos2: c.cos2.max(0.0),
                    ..c
                };
                b.power[i] = M::pow_cosine(c, s);
            }
        }
        // The usual exponents (shininess 2 to 128) in one pass.
        Power::Whole { n, cutoff } if n.is_power_of_two() && n <= 64 => match n.trailing_zeros() {
            0 => squared_block::<0, COS2>(b, cutoff),
            1 => squared_block::<1, COS2>(b, cutoff),
            2 => squared_block::<2, COS2>(b, cutoff),
            3 => squared_block::<3, COS2>(b, cutoff),
            4 => squared_block::<4, COS2>(b, cutoff),
            5 => squared_block::<5, COS2>(b, cutoff),
            _ => squared_block::<6, COS2>(b, cutoff),
        },
        Power::Whole { n, cutoff } => {
            let mut base = [0.0; BLOCK];
            for i in 0..BLOCK {
                base[i] = whole_base(stored_cosine::<COS2>(b, i), cutoff);
            }
            // Binary powering, one pass over the block per step.
            let mut n = n;
            let mut first = true;
            loop {
                if n & 1 == 1 {
                    if first {
                        b.power = base;
                        first = false;
                    } else {
                        for i in 0..BLOCK {
                            b.power[i] *= base[i];
                        }
                    }
                }
                n >>= 1;
                if n == 0 {
                    break;
                }
                for x in base.iter_mut() {
                    *x *= *x;
                }
            }
        }
    }
}

/// The stored cosine of lane `i`; with `COS2`, `sin²` = 1, which sends
/// [`whole_base`] to `cos²`.
#[inline(always)]
fn stored_cosine<const COS2: bool>(b: &Block, i: usize) -> Cosine {
    Cosine {
        positive: b.cos2[i] >= 0.0,
        sin2: if COS2 { 1.0 } else { b.sin2[i] },
        cos2: b.cos2[i],
    }
}

/// [`Power::Whole`] for `n = 2^K`: `K` squarings of each lane's base, in
/// registers, where binary powering for any `n` takes a pass over the block
/// per step.
#[inline(always)]
fn squared_block<const K: u32, const COS2: bool>(b: &mut Block, cutoff: f32) {
    for i in 0..BLOCK {
        let mut x = whole_base(stored_cosine::<COS2>(b, i), cutoff);
        for _ in 0..K {
            x *= x;
        }
        b.power[i] = x;
    }
}

/// Adds `gate · power · specular` of every lane to its colour (see
/// [`LightColors::separate`]); raw normals have their power in `power`
/// already. `specular` is the light's, times a constant spot factor.
#[inline(always)]
fn add_specular<M: Math, const RAW: bool, const COS2: bool>(
    b: &mut Block,
    light: &LightColors,
    specular: Vec3,
) {
    if !RAW {
        power_block::<M, COS2>(light.power, b);
    }
    let sum = if light.separate {
        &mut b.secondary
    } else {
        &mut b.primary
    };
    for i in 0..BLOCK {
        let f = b.gate[i] * b.power[i];
        for c in 0..3 {
            sum[c][i] = f.mul_add(specular[c], sum[c][i]);
        }
    }
}

/// The specular base of lane `i`, `n⊙ĥ` (Blinn-Phong) or `r⊙VP_e` (Phong),
/// and its `gate`. With unit normals the base is a cosine, stored for
/// [`power_block`], which raises it without losing the digits near 1; raw
/// normals take the plain power of the dot product, here. For an infinite
/// viewer `VP_e` is `eye` and `ĥ` (the halfway vector, not necessarily
/// normalised) comes in as `half` with `1/|ĥ|²`: the same for every vertex
/// where `FIXED_HALF` (a light at infinity), else that of the vertex, from
/// an [`Isa`] pass; a local viewer's of a light at infinity is a division
/// here. `COS2`: the base of a whole power, from `cos²` alone (see
/// [`Math::WHOLE_FROM_COS2`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn specular_base<
    M: Math,
    const LOCAL: bool,
    const PHONG: bool,
    const RAW: bool,
    const COS2: bool,
    const FIXED_HALF: bool,
>(
    b: &mut Block,
    i: usize,
    [n, vp, e]: [[f32; 3]; 3],
    n_dot_vp: f32,
    half: Half,
    eye: Vec3,
    shininess: f32,
    gate: f32,
) {
    let vp_e = if LOCAL { e } else { eye.to_array() };
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    b.gate[i] = gate;
    if PHONG {
        let r = [
            2.0 * n_dot_vp * n[0] - vp[0],
            2.0 * n_dot_vp * n[1] - vp[1],
            2.0 * n_dot_vp * n[2] - vp[2],
        ];
        if RAW {
            b.power[i] = M::pow(dot(r, vp_e), shininess);
        } else {
            store_cosine(b, i, cosine(r, vp_e));
        }
    } else {
        let h = if LOCAL {
            [vp[0] + e[0], vp[1] + e[1], vp[2] + e[2]]
        } else {
            half.h.to_array()
        };
        if RAW {
            b.power[i] = M::pow(dot(n, unit_and_length::<M>(h).0), shininess);
        } else {
            let inverse_h2 = if LOCAL && FIXED_HALF {
                1.0 / dot(h, h)
            } else {
                half.inverse_h2
            };
            if COS2 {
                let c = cos2_of_unit(n, h, inverse_h2);
                store_cos2(b, i, c.positive, c.cos2);
            } else {
                store_cosine(b, i, cosine_of_unit(n, h, inverse_h2));
            }
        }
    }
}

/// `n` scaled by the power of two that brings its largest component into
/// [1, 2), as f32: the scaling is exact, so the direction is `n`'s, and the
/// kernel normalises it without the range checks of [`unit_and_length`].
/// Zero stays zero.
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

/// `v` scaled by the power of two that brings its largest component into
/// [1, 2), so that its squared length neither overflows nor underflows f32 (a
/// light 1e20 or 1e-30 away); the scaling is exact. Returns the scaled
/// vector, its squared length raised to the smallest normal (so that an
/// [`Isa`] pass may take its `1/√`; a zero vector's stays there, and the
/// callers zero its inverse) and the factor that undoes the scaling.
#[inline(always)]
fn range_scaled(v: [f32; 3]) -> ([f32; 3], f32, f32) {
    let largest = v[0].abs().max(v[1].abs()).max(v[2].abs());
    // The biased exponent, kept where both 2^±(exponent − 127) are normal.
    let exponent = (largest.to_bits() >> 23).clamp(1, 253);
    let scale = f32::from_bits((254 - exponent) << 23); // 2^(127 − exponent)
    let unscale = f32::from_bits(exponent << 23); // 1/scale, exactly
    let w = [v[0] * scale, v[1] * scale, v[2] * scale];
    let len2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    (w, len2.max(f32::MIN_POSITIVE), unscale)
}

/// The unit vector along `v` and its length; zero for a zero vector. `v` is
/// first scaled by the power of two that brings its largest component into
/// [1, 2), so that its squared length neither overflows nor underflows f32 (a
/// light 1e20 or 1e-30 away); the scaling is exact.
#[inline(always)]
fn unit_and_length<M: Math>(v: [f32; 3]) -> ([f32; 3], f32) {
    let largest = v[0].abs().max(v[1].abs()).max(v[2].abs());
    // The biased exponent, kept where both 2^±(exponent − 127) are normal.
    let exponent = (largest.to_bits() >> 23).clamp(1, 253);
    let scale = f32::from_bits((254 - exponent) << 23); // 2^(127 − exponent)
    let unscale = f32::from_bits(exponent << 23); // 1/scale, exactly
    let w = [v[0] * scale, v[1] * scale, v[2] * scale];
    let len2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    let inv = M::rsqrt(len2.max(f32::MIN_POSITIVE));
    let inv = if len2 > 0.0 { inv } else { 0.0 };
    let len = len2 * inv * unscale;
    ([w[0] * inv, w[1] * inv, w[2] * inv], len)
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
