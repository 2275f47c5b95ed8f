//! Lighting a batch: the batch in tasks of [`TASK_VERTICES`] vertices on the rayon
//! pool, each task's blocks loaded, lit side by side and stored, by a task
//! function monomorphised for the scene's [`StateKey`] and built for an
//! [`InstructionSet`] (by default the widest the CPU has).

use std::mem::MaybeUninit;

use glam::Vec4;
use rayon::prelude::*;

use super::block::{BLOCK, Block};
#[cfg(target_arch = "x86_64")]
use super::isa::Avx512;
use super::isa::Plain;
use super::light::{SidePlan, light_side};
use super::variant::{Loop, Variant};
use super::{Colors, InstructionSet, Kernel, MaterialProducts, StateKey, Tier, Vertices};
use crate::LightMask;
use crate::fastmath::{Accurate, Fast, Math};

/// Vertices per rayon task: 64 blocks. A batch of one task runs on the
/// calling thread, without a hop to the pool, which would cost more than
/// the batch.
pub const TASK_VERTICES: usize = BLOCK * 64;

/// How many blocks ahead a task asks for its inputs and outputs. A block's
/// passes are too long for the CPU to look past them to the next block's
/// loads, so without prefetching each block waits for memory in turn (see
/// `docs/design.md` for the distances measured).
const PREFETCH_AHEAD: usize = 2;

impl Kernel {
    /// Lights every vertex in `material` with the evaluator of `tier`, in
    /// parallel on the current rayon pool.
    pub fn light(&self, tier: Tier, material: &MaterialProducts, vertices: &Vertices) -> Colors {
        self.light_on(InstructionSet::chosen(), tier, material, vertices)
    }

    /// [`Kernel::light`] with the build of `isa`, which the CPU must run
    /// (see [`InstructionSet::here`]); panics otherwise.
    pub fn light_on(
        &self,
        isa: InstructionSet,
        tier: Tier,
        material: &MaterialProducts,
        vertices: &Vertices,
    ) -> Colors {
        let mut colors = Colors::default();
        self.light_into_on(isa, tier, material, vertices, &mut colors);
        colors
    }

    /// [`Kernel::light`] into the buffers of `out`, which keep their memory
    /// from one call to the next: memory touched for the first time is slow
    /// to write.
    pub fn light_into(
        &self,
        tier: Tier,
        material: &MaterialProducts,
        vertices: &Vertices,
        out: &mut Colors,
    ) {
        self.light_into_on(InstructionSet::chosen(), tier, material, vertices, out);
    }

    fn light_into_on(
        &self,
        isa: InstructionSet,
        tier: Tier,
        material: &MaterialProducts,
        vertices: &Vertices,
        out: &mut Colors,
    ) {
        assert!(
            self.prepared(vertices),
            "vertices prepared by another kernel"
        );
        let run = task_function(isa, tier, self.state_key(material));
        let len = vertices.len;
        let front = &mut out.front;
        front.clear();
        front.reserve(len);
        if material.back.is_some() {
            out.back.get_or_insert_with(Vec::new).clear();
        } else {
            out.back = None;
        }
        let back = out.back.as_mut().map(|back| {
            back.reserve(len);
            &mut back.spare_capacity_mut()[..len]
        });
        let front_out = &mut front.spare_capacity_mut()[..len];
        let job = Job {
            kernel: self,
            material,
            vertices,
            in_range: self.lights_in_range(vertices),
        };
        if len <= TASK_VERTICES {
            run(&job, 0, front_out, back);
        } else {
            job.run_tasks(run, front_out, back);
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
}

/// What every task of one batch reads.
struct Job<'a> {
    kernel: &'a Kernel,
    material: &'a MaterialProducts,
    vertices: &'a Vertices,
    /// [`Kernel::lights_in_range`] of the batch.
    in_range: LightMask,
}

impl Job<'_> {
    /// Runs the task function on chunks of the batch in parallel.
    fn run_tasks(
        &self,
        run: TaskFn,
        front: &mut [MaybeUninit<Vec4>],
        back: Option<&mut [MaybeUninit<Vec4>]>,
    ) {
        let front_out = front.par_chunks_mut(TASK_VERTICES);
        match back {
            None => front_out
                .enumerate()
                .for_each(|(i, f)| run(self, i * TASK_VERTICES, f, None)),
            Some(back) => front_out
                .zip(back.par_chunks_mut(TASK_VERTICES))
                .enumerate()
                .for_each(|(i, (f, b))| run(self, i * TASK_VERTICES, f, Some(b))),
        }
    }
}

/// Lights the vertices from `start` on into `front` (and `back`), one block
/// at a time.
type TaskFn = fn(&Job, usize, &mut [MaybeUninit<Vec4>], Option<&mut [MaybeUninit<Vec4>]>);

/// The body of every task function: `side` lights one side of a block,
/// in the task function's build.
#[inline(always)]
fn run_task<V: Variant>(
    job: &Job,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    mut back: Option<&mut [MaybeUninit<Vec4>]>,
    side: SideFn,
) {
    let Job {
        kernel,
        material,
        vertices,
        in_range,
    } = *job;
    let separate = kernel.separate_specular();
    let front_plan = SidePlan::new::<V>(kernel, &material.front, in_range);
    let back_plan = material
        .back
        .as_ref()
        .map(|products| (products, SidePlan::new::<V>(kernel, products, in_range)));
    let mut block = SPARE_BLOCK.take().unwrap_or_default();
    // A batch of one task is small and was just written by its caller.
    let prefetch = vertices.len > TASK_VERTICES;
    for offset in (0..front.len()).step_by(BLOCK) {
        let end = (offset + BLOCK).min(front.len());
        let next = offset + PREFETCH_AHEAD * BLOCK;
        if prefetch && next + BLOCK <= front.len() {
            let back = back.as_deref().map(|b| &b[next..]);
            prefetch_block(kernel, vertices, start + next, &front[next..], back);
        }
        block.load::<V>(kernel, vertices, start + offset..start + end);
        // SAFETY: `side` is of the task function's build, which runs only
        // where the CPU has its instruction set.
        unsafe { side(&mut block, &front_plan, separate) };
        block.store(separate, material.front.alpha, &mut front[offset..end]);
        if let (Some((products, plan)), Some(out)) = (&back_plan, back.as_deref_mut()) {
            block.negate_normals();
            // SAFETY: as above.
            unsafe { side(&mut block, plan, separate) };
            block.store(separate, products.alpha, &mut out[offset..end]);
        }
    }
    SPARE_BLOCK.set(Some(block));
}

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
    /// Each thread's block between two tasks. A block is about 8.5 KB, and
    /// zeroing a new one costs as much as lighting a render tile's 256
    /// vertices. What the last task left in it is overwritten as within a
    /// task, where one block serves every 64 vertices in turn.
    static SPARE_BLOCK: std::cell::Cell<Option<Box<Block>>> = const { std::cell::Cell::new(None) };
}

/// The task function for a tier and a state key, in the build of `isa`.
fn task_function(isa: InstructionSet, tier: Tier, key: StateKey) -> TaskFn {
    assert!(isa.runs_here(), "this CPU does not run the {isa} build");
    match tier {
        Tier::Accurate => task_function_for::<Accurate>(isa, key),
        Tier::Fast => task_function_for::<Fast>(isa, key),
    }
}

fn task_function_for<M: Math>(isa: InstructionSet, key: StateKey) -> TaskFn {
    macro_rules! pick {
        ($($local:literal $spec:literal $phong:literal $raw:literal),*) => {
            match (key.local_viewer, key.specular, key.phong, key.raw_normals) {
                $(($local, $spec, $phong, $raw) => dispatch::<M, $local, $spec, $phong, $raw>(isa),)*
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

/// The build of `isa` of a task function (one the CPU runs: checked by
/// [`task_function`]).
fn dispatch<M: Math, const LOCAL: bool, const SPEC: bool, const PHONG: bool, const RAW: bool>(
    isa: InstructionSet,
) -> TaskFn {
    match isa {
        #[cfg(target_arch = "x86_64")]
        InstructionSet::Avx512 => |job, start, front, back| {
            // SAFETY: the CPU runs AVX-512F, AVX2 and FMA (`runs_here`).
            unsafe {
                task_avx512::<Loop<M, Avx512, LOCAL, SPEC, PHONG, RAW, false>>(
                    job, start, front, back,
                )
            }
        },
        #[cfg(target_arch = "x86_64")]
        InstructionSet::Avx2 => |job, start, front, back| {
            // SAFETY: the CPU runs AVX2 and FMA (`runs_here`).
            unsafe {
                task_avx2::<Loop<M, Plain, LOCAL, SPEC, PHONG, RAW, false>>(job, start, front, back)
            }
        },
        _ => task_plain::<Loop<M, Plain, LOCAL, SPEC, PHONG, RAW, false>>,
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
fn task_avx512<V: Variant>(
    job: &Job,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    back: Option<&mut [MaybeUninit<Vec4>]>,
) {
    run_task::<V>(job, start, front, back, side_avx512::<V>)
}

fn task_plain<V: Variant>(
    job: &Job,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    back: Option<&mut [MaybeUninit<Vec4>]>,
) {
    run_task::<V>(job, start, front, back, side_plain::<V>)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn task_avx2<V: Variant>(
    job: &Job,
    start: usize,
    front: &mut [MaybeUninit<Vec4>],
    back: Option<&mut [MaybeUninit<Vec4>]>,
) {
    run_task::<V>(job, start, front, back, side_avx2::<V>)
}

/// How a task function lights one side of a block: [`light_side`] in a
/// function of its own, built for the task function's instruction set
/// (`side_avx512`, `side_avx2`, `side_plain`) and not inlined into it.
/// Inlined, each variant's light loop was optimised twice (for the front
/// and for the back) inside one function of hundreds of kilobytes; split,
/// the lighting crate's release build takes about half the time and its
/// code is smaller, and a call per block and side costs nothing measurable
/// beside a block's work. Unsafe: the CPU must run the instruction set.
type SideFn = unsafe fn(&mut Block, &SidePlan, bool);

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
#[inline(never)]
fn side_avx512<V: Variant>(block: &mut Block, plan: &SidePlan, separate: bool) {
    light_side::<V>(block, plan, separate)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline(never)]
fn side_avx2<V: Variant>(block: &mut Block, plan: &SidePlan, separate: bool) {
    light_side::<V>(block, plan, separate)
}

#[inline(never)]
fn side_plain<V: Variant>(block: &mut Block, plan: &SidePlan, separate: bool) {
    light_side::<V>(block, plan, separate)
}
