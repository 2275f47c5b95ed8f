//! A port's per-vertex colours against GL's: one pass that evaluates GL
//! and every single deviation of the catalogue at once, in parallel over
//! tasks of vertices, and a second pass over pairs where no single
//! deviation explains the candidate.

use glam::{DVec3, Vec4};
use glint_lighting::deviation::{Deviation, Deviations};
use glint_lighting::{LightSet, Precision, Side, SurfaceMaterial, Viewer, bounding_box_centre};
use rayon::prelude::*;

use crate::diagnosis::{Diagnosis, ModelSums, Thresholds, diagnose};
use crate::eval::arith::{AccurateTier, Arith, FastTier, Real, Reference};
use crate::eval::dispatch::{self, Work};
use crate::eval::plan::{Pass, PassScene};
use crate::eval::{BLOCK, Block, Lanes, Points};
use crate::stats::{ColorLanes, ErrorStats, ErrorSums, Worst};

/// Vertices per parallel task: 64 blocks.
const TASK_VERTICES: usize = BLOCK * 64;

/// A validated shade request: what GL lights, and how precisely.
#[derive(Clone, Copy, Debug)]
pub struct Scene<'a> {
    pub lights: &'a LightSet,
    pub material: &'a SurfaceMaterial,
    pub positions: &'a [DVec3],
    /// One per position, as given (normalised here where the light model
    /// says so).
    pub normals: &'a [DVec3],
    pub precision: Precision,
    /// The viewer of the other kind than `lights.viewer`, which a port with
    /// [`Deviation::ViewerSwapped`] uses: see
    /// `glint_lighting::reference::Port::swapped_viewer`.
    pub swapped_viewer: Viewer,
}

/// The candidate's colours: RGBA per vertex, in the order of the vertices.
#[derive(Clone, Copy, Debug)]
pub struct Candidate<'a> {
    pub front: &'a [Vec4],
    /// The back colours, for a two-sided light model (compared with GL's
    /// back colours where given).
    pub back: Option<&'a [Vec4]>,
    /// Whether alpha is compared (the candidate gave it): alpha enters the
    /// diagnosis and `ErrorStats::alpha_max_abs`, never the RGB figures.
    pub alpha: bool,
}

/// How much to report, and what "explains" means.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// How many of the worst vertices to return.
    pub worst: usize,
    /// A deviation explains the candidate where the largest error it
    /// leaves is within this; `None`: the tier's bound.
    pub tolerance: Option<f64>,
}

/// The contract's default number of worst vertices.
pub const DEFAULT_WORST: usize = 10;

impl Default for Options {
    fn default() -> Self {
        Self {
            worst: DEFAULT_WORST,
            tolerance: None,
        }
    }
}

/// Which colour of which vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexAt {
    pub vertex: usize,
    pub side: Side,
}

/// The candidate against GL.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// Over the RGB channels of every compared colour (front, and back
    /// where given).
    pub error: ErrorStats,
    /// The vertices with the largest error, worst first, each with GL's
    /// colour (from the evaluator of the scene's precision) and the
    /// candidate's. GL's term breakdown is the reference's,
    /// `glint_lighting::reference::evaluate`.
    pub worst: Vec<Worst<VertexAt>>,
    pub diagnosis: Diagnosis,
    /// The documented bound of the scene's precision.
    pub bound: f64,
    /// What "explains" meant.
    pub tolerance: f64,
}

/// The largest magnitude of a candidate's channel. A port's colours are
/// near [0, 1]; this bound keeps every error, its square and their sums
/// over a task's blocks, accumulated in f32 lanes, far from f32's range
/// (1e6 squared is 1e12, against 3.4e38), so the mean, the p99 and PSNR
/// stay finite numbers.
pub const MAX_CHANNEL: f32 = 1e6;

/// A candidate that cannot be compared with the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CandidateError {
    /// Not one colour per vertex.
    Count {
        side: Side,
        colors: usize,
        vertices: usize,
    },
    /// Back colours for a light model that is not two-sided.
    BackWithoutTwoSide,
    /// A channel outside ±[`MAX_CHANNEL`]: NaN, infinite, or too large
    /// for the error's sums.
    OutOfRange {
        side: Side,
        vertex: usize,
        channel: usize,
    },
}

impl CandidateError {
    /// The JSON Pointer of the fault in a compare request
    /// (`/candidate/colors/17/2`; back colours are `/candidate/back_colors`).
    pub fn pointer(&self) -> String {
        let colors = |side: &Side| match side {
            Side::Front => "/candidate/colors",
            Side::Back => "/candidate/back_colors",
        };
        match self {
            CandidateError::Count { side, .. } => colors(side).to_owned(),
            CandidateError::BackWithoutTwoSide => colors(&Side::Back).to_owned(),
            CandidateError::OutOfRange {
                side,
                vertex,
                channel,
            } => format!("{}/{vertex}/{channel}", colors(side)),
        }
    }
}

impl std::fmt::Display for CandidateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CandidateError::Count {
                colors, vertices, ..
            } => write!(
                f,
                "{colors} colours for {vertices} vertices: give one colour per vertex"
            ),
            CandidateError::BackWithoutTwoSide => {
                f.write_str("back colours for a light model that is not two-sided")
            }
            CandidateError::OutOfRange { .. } => write!(
                f,
                "a colour channel must be a number in [-{MAX_CHANNEL:e}, {MAX_CHANNEL:e}]"
            ),
        }
    }
}

impl std::error::Error for CandidateError {}

/// Colours per parallel chunk of [`Candidate::check`].
const CHECK_CHUNK: usize = 1 << 14;

impl Candidate<'_> {
    /// Whether the candidate fits `scene`: one colour per vertex, each
    /// channel within ±[`MAX_CHANNEL`],
    /// back colours only for a two-sided light model.
    pub fn check(&self, scene: &Scene) -> Result<(), CandidateError> {
        if self.back.is_some() && !scene.lights.model.two_side {
            return Err(CandidateError::BackWithoutTwoSide);
        }
        let vertices = scene.positions.len();
        let sides = std::iter::once((Side::Front, self.front))
            .chain(self.back.map(|back| (Side::Back, back)));
        for (side, colors) in sides {
            if colors.len() != vertices {
                return Err(CandidateError::Count {
                    side,
                    colors: colors.len(),
                    vertices,
                });
            }
            // A NaN fails the comparison too. Each chunk is tested in one
            // branch-free pass that vectorises; only a chunk that fails is
            // searched for its first fault.
            let inside = |x: f32| x.abs() <= MAX_CHANNEL;
            let chunk_inside = |chunk: &[Vec4]| {
                chunk.iter().fold(true, |all, c| {
                    all & c.to_array().into_iter().fold(true, |a, x| a & inside(x))
                })
            };
            let failing = colors
                .par_chunks(CHECK_CHUNK)
                .position_first(|chunk| !chunk_inside(chunk));
            if let Some(chunk) = failing {
                let start = chunk * CHECK_CHUNK;
                let (vertex, channel) = colors[start..]
                    .iter()
                    .enumerate()
                    .find_map(|(i, c)| {
                        let channel = c.to_array().into_iter().position(|x| !inside(x))?;
                        Some((start + i, channel))
                    })
                    .expect("a chunk that fails holds a channel out of range");
                return Err(CandidateError::OutOfRange {
                    side,
                    vertex,
                    channel,
                });
            }
        }
        Ok(())
    }
}

/// Compares `candidate` with GL's colours of `scene`, and diagnoses it.
///
/// # Panics
///
/// If the scene has not one normal per position.
pub fn compare(
    scene: &Scene,
    candidate: &Candidate,
    options: &Options,
) -> Result<Comparison, CandidateError> {
    assert_eq!(scene.positions.len(), scene.normals.len());
    candidate.check(scene)?;
    Ok(match scene.precision {
        Precision::Reference => compare_in::<Reference>(scene, candidate, options),
        Precision::Accurate => compare_in::<AccurateTier>(scene, candidate, options),
        Precision::Fast => compare_in::<FastTier>(scene, candidate, options),
    })
}

/// The deviations worth a model in this comparison: all but those whose
/// channel is not compared.
pub(crate) fn catalogue(alpha: bool, back: bool) -> Vec<Deviation> {
    Deviation::ALL
        .into_iter()
        .filter(|d| match d {
            Deviation::AlphaSummed => alpha,
            Deviation::TwoSideIgnored => back,
            _ => true,
        })
        .collect()
}

/// The singles of `catalogue` that change something of this scene's
/// colours by their plan (a light's term, a constant term, the output), and
/// those that cannot.
pub(crate) fn observable_singles<A: Arith>(
    scene: &PassScene,
    catalogue: &[Deviation],
) -> (Vec<Deviations>, Vec<Deviation>) {
    let models: Vec<Deviations> = std::iter::once(Deviations::NONE)
        .chain(catalogue.iter().map(|&d| d.into()))
        .collect();
    let pass = Pass::<A>::new(scene, &models);
    let gl = pass.models[0];
    let (mut observable, mut not) = (Vec::new(), Vec::new());
    for (m, &d) in catalogue.iter().enumerate() {
        let m = m + 1;
        let model = pass.models[m];
        let sides = if scene.back { 2 } else { 1 };
        let changes = pass.sides.iter().any(|material| {
            material[..sides]
                .iter()
                .any(|s| s.model_touches[m] || s.model_bases[m] != s.base)
        }) || model.separate != gl.separate
            || model.clamp != gl.clamp
            || model.srgb
            || (model.front_for_back && scene.back)
            || (model.alpha_summed && scene.alpha);
        if changes {
            observable.push(d.into());
        } else {
            not.push(d);
        }
    }
    (observable, not)
}

fn compare_in<A: Arith>(scene: &Scene, candidate: &Candidate, options: &Options) -> Comparison {
    let bound = scene.precision.max_abs_error();
    let tolerance = options.tolerance.unwrap_or(bound);
    let lights = scene.lights;
    // Positions matter where a light is at a point or a viewer is: GL's, or
    // the other kind a port with the viewer swapped uses.
    let positions =
        lights.depends_on_position() || matches!(scene.swapped_viewer, Viewer::Local(_));
    let centre = if positions {
        bounding_box_centre(scene.positions)
    } else {
        DVec3::ZERO
    };
    let points = Points::new(
        scene.positions,
        scene.normals,
        lights.model.normalize_normals,
        positions.then_some(centre),
    );
    let pass_scene = PassScene {
        lights,
        swapped_viewer: scene.swapped_viewer,
        materials: std::slice::from_ref(scene.material),
        centre,
        unnormalized_normals: points.unnormalized(),
        alpha: candidate.alpha,
        back: candidate.back.is_some(),
    };
    let (singles, structurally_unobservable) = observable_singles::<A>(
        &pass_scene,
        &catalogue(candidate.alpha, candidate.back.is_some()),
    );
    let models: Vec<Deviations> = std::iter::once(Deviations::NONE)
        .chain(singles.iter().copied())
        .collect();
    let pass = Pass::<A>::new(&pass_scene, &models);
    let sides = 1 + usize::from(candidate.back.is_some());
    let mut errors = vec![0.0f32; 3 * sides * points.len];
    let mut first = run_pass(&pass, &points, candidate, options.worst, Some(&mut errors));
    let channels = sides * points.len * if candidate.alpha { 4 } else { 3 };
    let diagnosis = diagnose(
        &singles,
        &first.models,
        structurally_unobservable,
        channels,
        Thresholds { bound, tolerance },
        |pairs| {
            let pass = Pass::<A>::new(&pass_scene, pairs);
            run_pass(&pass, &points, candidate, 0, None).models
        },
    );
    Comparison {
        error: first.gl.stats(&errors, bound, candidate.alpha),
        worst: first.gl.worst.into_sorted(),
        diagnosis,
        bound,
        tolerance,
    }
}

/// The sums of one pass: GL's error and each model's.
struct PassSums {
    gl: ErrorSums<VertexAt>,
    models: Vec<ModelSums>,
}

impl PassSums {
    fn merge(self, other: Self) -> Self {
        Self {
            gl: self.gl.merge(other.gl),
            models: self
                .models
                .iter()
                .zip(other.models)
                .map(|(a, b)| a.merge(b))
                .collect(),
        }
    }
}

/// What every task of a pass reads.
struct Job<'a, A: Arith> {
    pass: &'a Pass<A>,
    points: &'a Points<A::F>,
    candidate: &'a Candidate<'a>,
    worst: usize,
}

/// One pass over every vertex, in parallel: GL's error (its channel errors
/// into `errors`, front then back, where given) and each model's sums.
fn run_pass<A: Arith>(
    pass: &Pass<A>,
    points: &Points<A::F>,
    candidate: &Candidate,
    worst: usize,
    errors: Option<&mut Vec<f32>>,
) -> PassSums {
    let job = Job {
        pass,
        points,
        candidate,
        worst,
    };
    let len = points.len;
    let tasks = len.div_ceil(TASK_VERTICES);
    let task = |t: usize, front_errors, back_errors| {
        dispatch::run(Task {
            job: &job,
            start: t * TASK_VERTICES,
            front_errors,
            back_errors,
        })
    };
    let empty = || PassSums {
        gl: ErrorSums::new(worst),
        models: vec![ModelSums::default(); pass.models.len()],
    };
    let Some(errors) = errors else {
        return (0..tasks)
            .into_par_iter()
            .map(|t| task(t, None, None))
            .reduce(empty, PassSums::merge);
    };
    let (front, back) = errors.split_at_mut(3 * len);
    let front = front.par_chunks_mut(3 * TASK_VERTICES);
    if candidate.back.is_some() {
        front
            .zip(back.par_chunks_mut(3 * TASK_VERTICES))
            .enumerate()
            .map(|(t, (f, b))| task(t, Some(f), Some(b)))
            .reduce(empty, PassSums::merge)
    } else {
        front
            .enumerate()
            .map(|(t, f)| task(t, Some(f), None))
            .reduce(empty, PassSums::merge)
    }
}

/// A task: the vertices from `start` on (at most [`TASK_VERTICES`]), GL's
/// channel errors into the slices given.
struct Task<'a, A: Arith> {
    job: &'a Job<'a, A>,
    start: usize,
    front_errors: Option<&'a mut [f32]>,
    back_errors: Option<&'a mut [f32]>,
}

impl<A: Arith> Work for Task<'_, A> {
    type Out = PassSums;

    #[inline(always)]
    fn run(self) -> PassSums {
        let Task {
            job,
            start,
            mut front_errors,
            mut back_errors,
        } = self;
        let Job {
            pass,
            points,
            candidate,
            worst,
        } = *job;
        let end = (start + TASK_VERTICES).min(points.len);
        let mut gl = ErrorSums::new(worst);
        let mut models = vec![ModelLanes::<A::F>::ZERO; pass.models.len()];
        let mut block = Block::new(pass);
        let mut lanes = CandidateLanes::<A::F>::default();
        for offset in (start..end).step_by(BLOCK) {
            let range = offset..(offset + BLOCK).min(end);
            let local = (range.start - start) * 3..(range.end - start) * 3;
            let sides =
                std::iter::once((Side::Front, candidate.front, front_errors.as_deref_mut())).chain(
                    candidate
                        .back
                        .map(|back| (Side::Back, back, back_errors.as_deref_mut())),
                );
            for (side, colors, errors) in sides {
                block.load(pass, points, range.clone(), side);
                block.evaluate(pass, 0, side);
                lanes.load(&colors[range.clone()]);
                if let Some(errors) = errors {
                    add_gl_error(
                        &mut gl,
                        &block,
                        &lanes,
                        range.start,
                        side,
                        &mut errors[local.clone()],
                    );
                }
                for (m, model) in models.iter_mut().enumerate() {
                    let clamped = pass.models[m].clamp;
                    model.add(&block, m, &lanes, candidate.alpha, clamped);
                }
            }
        }
        gl.flush();
        PassSums {
            gl,
            models: models.iter().map(ModelLanes::total).collect(),
        }
    }
}

/// A block's candidate colours as lanes.
struct CandidateLanes<F> {
    len: usize,
    rgba: [Lanes<F>; 4],
}

impl<F: Real> Default for CandidateLanes<F> {
    fn default() -> Self {
        Self {
            len: 0,
            rgba: [[F::zero(); BLOCK]; 4],
        }
    }
}

impl<F: Real> CandidateLanes<F> {
    #[inline(always)]
    fn load(&mut self, colors: &[Vec4]) {
        self.len = colors.len();
        for (i, c) in colors.iter().enumerate() {
            for (channel, lanes) in self.rgba.iter_mut().enumerate() {
                lanes[i] = F::of(f64::from(c[channel]));
            }
        }
        for lanes in &mut self.rgba {
            lanes[colors.len()..].fill(F::zero());
        }
    }
}

/// Adds a block's GL error: GL's colours (model 0) against the candidate's.
#[inline(always)]
fn add_gl_error<A: Arith>(
    gl: &mut ErrorSums<VertexAt>,
    block: &Block<A>,
    candidate: &CandidateLanes<A::F>,
    start: usize,
    side: Side,
    errors: &mut [f32],
) {
    let narrow = |lanes: &[Lanes<A::F>; 4]| -> ColorLanes {
        std::array::from_fn(|c| std::array::from_fn(|i| lanes[c][i].wide() as f32))
    };
    let mask: [f32; BLOCK] = std::array::from_fn(|i| block.mask[i].wide() as f32);
    let back = u64::from(side == Side::Back);
    gl.add_block(
        &narrow(&block.colors[0]),
        &narrow(&candidate.rgba),
        &mask,
        block.len,
        errors,
        |i| {
            let at = VertexAt {
                vertex: start + i,
                side,
            };
            (at, 2 * (start + i) as u64 + back)
        },
    );
}

/// Per lane, one model's sums over the blocks of a task: summed once per
/// task.
#[derive(Clone, Copy)]
struct ModelLanes<F> {
    max: Lanes<F>,
    sum: Lanes<F>,
    shift: Lanes<F>,
}

impl<F: Real> ModelLanes<F> {
    const ZERO: Self = Self {
        max: [F::ZERO; BLOCK],
        sum: [F::ZERO; BLOCK],
        shift: [F::ZERO; BLOCK],
    };

    /// Adds model `m`'s colours of a block: its error against the
    /// candidate, and how far it is from GL's (model 0). `clamped`: the
    /// model's colours are in [0, 1], so that [`residual`]'s division is 1.
    #[inline(always)]
    fn add<A: Arith<F = F>>(
        &mut self,
        block: &Block<A>,
        m: usize,
        candidate: &CandidateLanes<F>,
        alpha: bool,
        clamped: bool,
    ) {
        let colors = &block.colors[m];
        let gl = &block.colors[0];
        let channels = if alpha { 4 } else { 3 };
        for c in 0..channels {
            let (want, color, gl) = (&candidate.rgba[c], &colors[c], &gl[c]);
            if clamped {
                for i in 0..BLOCK {
                    let e = (want[i] - color[i]).abs() * block.mask[i];
                    self.max[i] = self.max[i].larger(e);
                    self.sum[i] += e;
                    let moved = (gl[i] - color[i]).abs() * block.mask[i];
                    self.shift[i] = self.shift[i].larger(moved);
                }
            } else {
                for i in 0..BLOCK {
                    let e = residual(want[i], color[i]) * block.mask[i];
                    self.max[i] = self.max[i].larger(e);
                    self.sum[i] += e;
                    let moved = residual(gl[i], color[i]) * block.mask[i];
                    self.shift[i] = self.shift[i].larger(moved);
                }
            }
        }
    }

    fn total(&self) -> ModelSums {
        let most = |x: &Lanes<F>| x.iter().fold(0.0f64, |m, v| m.max(v.wide()));
        ModelSums {
            max: most(&self.max),
            sum: self.sum.iter().map(|v| v.wide()).sum(),
            shift: most(&self.shift),
        }
    }
}

/// How far `value` is from a model's `color`: the difference, relative to
/// the colour where it exceeds 1 (an unclamped colour of 1e4 holds the
/// relative error of the tier's powers, and a port's own f32 rounding, in
/// absolute units far above any bound).
#[inline(always)]
pub(crate) fn residual<F: Real>(value: F, color: F) -> F {
    (value - color).abs() / color.abs().max(F::one())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glint_lighting::{Light, LightModel, Material};

    /// The first channel out of range is found wherever it lies among the
    /// chunks that are checked in parallel, before a later one, and a
    /// candidate in range passes.
    #[test]
    fn the_first_fault_of_a_long_candidate_is_named() {
        let vertices = 3 * CHECK_CHUNK + 17;
        let lights = LightSet::new(
            LightModel::default(),
            vec![Light::default()],
            LightSet::eye_space_viewer(false),
        )
        .unwrap();
        let material = SurfaceMaterial::both_sides(Material::default());
        let positions = vec![DVec3::ZERO; vertices];
        let normals = vec![DVec3::Z; vertices];
        let scene = Scene {
            lights: &lights,
            material: &material,
            positions: &positions,
            normals: &normals,
            precision: Precision::Fast,
            swapped_viewer: Viewer::Local(DVec3::ZERO),
        };
        let mut colors = vec![Vec4::splat(0.5); vertices];
        let check = |colors: &[Vec4]| {
            Candidate {
                front: colors,
                back: None,
                alpha: false,
            }
            .check(&scene)
        };
        assert_eq!(check(&colors), Ok(()));
        // Past the first chunk, at the edge of the range: still inside.
        colors[CHECK_CHUNK + 3].x = -MAX_CHANNEL;
        assert_eq!(check(&colors), Ok(()));
        for (vertex, channel, value) in [
            (vertices - 1, 3, f32::INFINITY),
            (2 * CHECK_CHUNK + 5, 1, MAX_CHANNEL * 1.001),
            (CHECK_CHUNK + 9, 2, f32::NAN),
        ] {
            colors[vertex][channel] = value;
            assert_eq!(
                check(&colors),
                Err(CandidateError::OutOfRange {
                    side: Side::Front,
                    vertex,
                    channel,
                })
            );
        }
    }
}
