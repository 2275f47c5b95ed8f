//! The evaluator of many ports at once: GL's colour and the colour of every
//! model of a [`Pass`] (a deviation, or a pair), for blocks of 64 points.
//!
//! The models share everything they can. A block is loaded once (positions
//! recentred, normals, as the kernels hold them: f32 structure of arrays,
//! or f64 for the reference tier). For each light, GL's geometry (`VP_pli`,
//! the attenuation, the spot cosine and factor), `n·VP_pli` and the
//! specular power are computed once, and GL's terms are summed. Then each
//! variant of a factor that some model reads (another spot factor, diffuse
//! base or specular power) is computed once, and each model that changes
//! this light adds the difference its variants make to its own sums (see
//! [`plan`]). A model that changes no light (the constant terms, the
//! output) costs only its final colour.
//!
//! The f32 tiers take their powers and cosines from the kernels' own
//! arithmetic ([`arith`]), so that each model's colour is within the tier's
//! documented bound of the reference evaluator's colour for that port
//! (`glint_lighting::reference::color_port`), as the tier's shade is of
//! GL's. As in the kernels, the bound holds where the equation is
//! continuous: a point within an f32 rounding of a spot cone's edge may
//! fall on the other side of it.
//!
//! A model's sums are GL's plus its differences. Where GL has a term so
//! large that taking it away would cost the rounding of that term (a
//! specular power near its cap of 1e10, an attenuation of 1e4), the block
//! is evaluated again in *direct* mode, each model summing its own terms
//! ([`Pass::direct_above`]).

pub(crate) mod arith;
pub(crate) mod dispatch;
pub(crate) mod plan;

use glam::DVec3;
use glint_lighting::{LightMask, MAX_POWER, MAX_RAW_NORMAL, Side, SpecularModel, unit_or_zero};
use rayon::prelude::*;

use arith::{Arith, Real};
use num_traits::{Float, One, Zero};
use plan::{
    DiffuseKey, ModelLight, Pass, PowerPlan, SidePlan, Source, SpotPower, SpotVariant, ViewerPlan,
};

/// Points per block: the working set of a pass stays in L1.
pub(crate) const BLOCK: usize = 64;

/// One lane's value per point of a block.
pub(crate) type Lanes<F> = [F; BLOCK];

/// A batch of points in the form the lanes read: structure of arrays,
/// positions recentred, normals of unit length (or as given, where the
/// scene does not normalise them).
#[derive(Clone, Debug, Default)]
pub(crate) struct Points<F> {
    pub len: usize,
    /// Empty where the pass reads no position.
    pub positions: [Vec<F>; 3],
    pub normals: [Vec<F>; 3],
    /// Where the normals are normalised: their own lengths, capped at
    /// [`MAX_RAW_NORMAL`] (a port that does not normalise reads them).
    pub lengths: Vec<F>,
    /// Per point, which lights reach it (the renderer's shadows).
    pub visible: Option<Vec<LightMask>>,
}

/// Points per parallel chunk of a conversion.
const CONVERSION_CHUNK: usize = 1 << 14;

impl<F: Real> Points<F> {
    /// The points with `normals` (normalised where `normalize`), and the
    /// `positions` recentred on `centre` where it is given, converted in
    /// parallel on the current rayon pool.
    pub fn new(
        positions: &[DVec3],
        normals: &[DVec3],
        normalize: bool,
        centre: Option<DVec3>,
    ) -> Self {
        let len = normals.len();
        let zeros = || vec![F::ZERO; len];
        let mut points = Points {
            len,
            normals: [zeros(), zeros(), zeros()],
            ..Points::default()
        };
        let [x, y, z] = &mut points.normals;
        let axes = x
            .par_chunks_mut(CONVERSION_CHUNK)
            .zip(y.par_chunks_mut(CONVERSION_CHUNK))
            .zip(z.par_chunks_mut(CONVERSION_CHUNK))
            .zip(normals.par_chunks(CONVERSION_CHUNK));
        if normalize {
            points.lengths = zeros();
            axes.zip(points.lengths.par_chunks_mut(CONVERSION_CHUNK))
                .for_each(|((((x, y), z), from), lengths)| {
                    for (i, &n) in from.iter().enumerate() {
                        let (unit, length) = unit_and_length(n);
                        (x[i], y[i], z[i]) = (F::of(unit.x), F::of(unit.y), F::of(unit.z));
                        lengths[i] = F::of(length.min(MAX_RAW_NORMAL));
                    }
                });
        } else {
            axes.for_each(|(((x, y), z), from)| {
                for (i, n) in from.iter().enumerate() {
                    (x[i], y[i], z[i]) = (F::of(n.x), F::of(n.y), F::of(n.z));
                }
            });
        }
        if let Some(centre) = centre {
            points.positions = [zeros(), zeros(), zeros()];
            let [x, y, z] = &mut points.positions;
            x.par_chunks_mut(CONVERSION_CHUNK)
                .zip(y.par_chunks_mut(CONVERSION_CHUNK))
                .zip(z.par_chunks_mut(CONVERSION_CHUNK))
                .zip(positions.par_chunks(CONVERSION_CHUNK))
                .for_each(|(((x, y), z), from)| {
                    for (i, &p) in from.iter().enumerate() {
                        let p = p - centre;
                        (x[i], y[i], z[i]) = (F::of(p.x), F::of(p.y), F::of(p.z));
                    }
                });
        }
        points
    }

    /// Whether some normal is not of unit length (beyond f64 rounding), so
    /// that a port that does not normalise them draws something else than
    /// GL. False where the scene does not normalise.
    pub fn unnormalized(&self) -> bool {
        self.lengths
            .par_chunks(CONVERSION_CHUNK)
            .any(|chunk| chunk.iter().any(|l| (l.wide() - 1.0).abs() > 1e-12))
    }
}

/// `n` to unit length (zero for a zero or non-finite vector) and its
/// length: [`unit_or_zero`] and `n.length()`. Where `|n|²` is well inside
/// f64's range (every normal a scene sends), one square root and one
/// division serve both, within an f64 rounding or two of
/// [`unit_or_zero`]'s quotients: far below f32's, and the reference tier's,
/// resolution. Elsewhere [`unit_or_zero`] scales first.
#[inline(always)]
fn unit_and_length(n: DVec3) -> (DVec3, f64) {
    let length2 = n.length_squared();
    if <f64 as Real>::SAFE_DISTANCE2.contains(&length2) {
        let length = length2.sqrt();
        return (n * (1.0 / length), length);
    }
    (unit_or_zero(n), n.length())
}

/// Whether any of `normals` is not of unit length (see
/// [`Points::unnormalized`]).
pub(crate) fn unnormalized(normals: &[DVec3]) -> bool {
    normals
        .par_chunks(CONVERSION_CHUNK)
        .any(|chunk| chunk.iter().any(|n| (n.length() - 1.0).abs() > 1e-12))
}

/// The working set of one block: its points, GL's sums, one light's
/// factors and variants, and each model's differences and colours.
pub(crate) struct Block<A: Arith> {
    /// Points in the block (the lanes past them repeat its last position,
    /// with a zero normal).
    pub len: usize,
    /// 1 in the lanes of points, 0 past them.
    pub mask: Lanes<A::F>,
    p: [Lanes<A::F>; 3],
    n: [Lanes<A::F>; 3],
    length: Lanes<A::F>,
    vp_e: [Lanes<A::F>; 3],
    vp_e_swapped: [Lanes<A::F>; 3],
    masks: Option<[LightMask; BLOCK]>,
    ones: Lanes<A::F>,
    // GL's sums.
    primary: [Lanes<A::F>; 3],
    secondary: [Lanes<A::F>; 3],
    alpha_sum: Lanes<A::F>,
    // One light's factors.
    vp: [Lanes<A::F>; 3],
    distance: Lanes<A::F>,
    att: Lanes<A::F>,
    spot_cos: Lanes<A::F>,
    spot_sin2: Lanes<A::F>,
    spot_stored: Lanes<A::F>,
    spot_power: Lanes<A::F>,
    spot: Lanes<A::F>,
    visible: Lanes<A::F>,
    n_dot_vp: Lanes<A::F>,
    lit: Lanes<A::F>,
    /// GL's diffuse base: `(n⊙VP_pli)` times the visibility.
    diffuse_base: Lanes<A::F>,
    gate: Lanes<A::F>,
    power: Lanes<A::F>,
    sa: Lanes<A::F>,
    sd: Lanes<A::F>,
    ss: Lanes<A::F>,
    sin2: Lanes<A::F>,
    cos: Lanes<A::F>,
    base: Lanes<A::F>,
    /// `|n|^s` for the exponent beside it, for the side being evaluated.
    length_power: Lanes<A::F>,
    length_power_of: Option<A::F>,
    spot_variants: Vec<Lanes<A::F>>,
    diffuse_variants: Vec<Lanes<A::F>>,
    power_variants: Vec<Lanes<A::F>>,
    /// Per model: the differences of its sums from GL's (in direct mode,
    /// its sums of the lights' terms): primary RGB, secondary RGB, alpha.
    deltas: Vec<[Lanes<A::F>; 7]>,
    /// Per model: its colour, RGBA.
    pub colors: Vec<[Lanes<A::F>; 4]>,
    /// Per model: its front colour, kept for a back side that takes it.
    front: Vec<[Lanes<A::F>; 4]>,
    /// Per lane, the largest magnitude of a GL term.
    largest_term: Lanes<A::F>,
    /// Each model sums its own terms (see [`Pass::direct_above`]).
    direct: bool,
    /// The light of the factors is at infinity: `VP_pli` is the same in
    /// every lane.
    directional: bool,
}

impl<A: Arith> Block<A> {
    pub fn new(pass: &Pass<A>) -> Box<Self> {
        let zero = [A::F::zero(); BLOCK];
        let models = pass.models.len();
        let most = |count: &dyn Fn(&plan::SideLight<A>) -> usize| {
            pass.sides
                .iter()
                .flatten()
                .flat_map(|s| s.lights.iter())
                .map(count)
                .max()
                .unwrap_or(0)
        };
        let spot_variants = pass
            .lights
            .iter()
            .map(|l| l.spot_variants.len())
            .max()
            .unwrap_or(0);
        Box::new(Self {
            len: 0,
            mask: zero,
            p: [zero; 3],
            n: [zero; 3],
            length: zero,
            vp_e: [zero; 3],
            vp_e_swapped: [zero; 3],
            masks: None,
            ones: [A::F::one(); BLOCK],
            primary: [zero; 3],
            secondary: [zero; 3],
            alpha_sum: zero,
            vp: [zero; 3],
            distance: zero,
            att: zero,
            spot_cos: zero,
            spot_sin2: zero,
            spot_stored: zero,
            spot_power: zero,
            spot: zero,
            visible: [A::F::one(); BLOCK],
            n_dot_vp: zero,
            lit: zero,
            diffuse_base: zero,
            gate: zero,
            power: zero,
            sa: zero,
            sd: zero,
            ss: zero,
            sin2: zero,
            cos: zero,
            base: zero,
            length_power: zero,
            length_power_of: None,
            spot_variants: vec![zero; spot_variants],
            diffuse_variants: vec![zero; most(&|l| l.diffuse_variants.len())],
            power_variants: vec![zero; most(&|l| l.power_variants.len())],
            deltas: vec![[zero; 7]; models],
            colors: vec![[zero; 4]; models],
            front: vec![[zero; 4]; models],
            largest_term: zero,
            direct: false,
            directional: false,
        })
    }

    /// Loads the points of `range` (at most [`BLOCK`]) for `side`: the
    /// back side has the negated normals.
    #[inline(always)]
    pub fn load(
        &mut self,
        pass: &Pass<A>,
        points: &Points<A::F>,
        range: std::ops::Range<usize>,
        side: Side,
    ) {
        let count = range.len();
        self.len = count;
        let zero = A::F::zero();
        let one = A::F::one();
        for i in 0..BLOCK {
            self.mask[i] = if i < count { one } else { zero };
        }
        let sign = match side {
            Side::Front => one,
            Side::Back => -one,
        };
        for axis in 0..3 {
            let normals = &points.normals[axis][range.clone()];
            for i in 0..count {
                self.n[axis][i] = sign * normals[i];
            }
            self.n[axis][count..].fill(zero);
            if pass.positions {
                let positions = &points.positions[axis][range.clone()];
                self.p[axis][..count].copy_from_slice(positions);
                // Lanes past the batch repeat its last point, so that they are
                // as far from each light as a real one.
                let last = self.p[axis][count - 1];
                self.p[axis][count..].fill(last);
            }
        }
        if pass.raw_lengths {
            self.length[..count].copy_from_slice(&points.lengths[range.clone()]);
            self.length[count..].fill(zero);
        }
        self.masks = points.visible.as_ref().map(|visible| {
            let mut masks = [LightMask::MAX; BLOCK];
            masks[..count].copy_from_slice(&visible[range]);
            masks
        });
        if let ViewerPlan::Local(eye) = pass.viewer {
            self.eye_directions(eye, false);
        }
        if let Some(ViewerPlan::Local(eye)) = pass.swapped_viewer {
            self.eye_directions(eye, true);
        }
    }

    /// `VP_e` of every lane for a local viewer at `eye`.
    #[inline(always)]
    fn eye_directions(&mut self, eye: [A::F; 3], swapped: bool) {
        let mut d = [[A::F::zero(); BLOCK]; 3];
        for axis in 0..3 {
            for i in 0..BLOCK {
                d[axis][i] = eye[axis] - self.p[axis][i];
            }
        }
        let mut distance = [A::F::zero(); BLOCK];
        normalize_lanes(&mut d, &mut distance);
        if swapped {
            self.vp_e_swapped = d;
        } else {
            self.vp_e = d;
        }
    }

    /// Evaluates every model of `pass` on the loaded block, for `side` of
    /// `material`, into [`Block::colors`]. A back side whose models take the
    /// front colour needs the front side evaluated on the same points just
    /// before.
    #[inline(always)]
    pub fn evaluate(&mut self, pass: &Pass<A>, material: usize, side: Side) {
        let side_index = match side {
            Side::Front => 0,
            Side::Back => 1,
        };
        let plan = &pass.sides[material][side_index];
        self.length_power_of = None;
        self.direct = false;
        self.evaluate_models(pass, plan, side);
        if pass.models.len() > 1 && self.largest_term.iter().any(|&t| t > pass.direct_above) {
            self.direct = true;
            self.evaluate_models(pass, plan, side);
        }
    }

    /// [`Block::evaluate`] in the block's mode.
    #[inline(always)]
    fn evaluate_models(&mut self, pass: &Pass<A>, plan: &SidePlan<A>, side: Side) {
        // What a model that changes nothing of a light adds in direct mode:
        // GL's terms.
        const GL_TERMS: ModelLight = ModelLight {
            attenuation_one: false,
            spot: None,
            ambient_unspotted: false,
            ambient_off: false,
            diffuse: None,
            ungated: false,
            power: None,
            ambient_term: true,
            diffuse_term: true,
            specular_term: true,
        };
        self.start_sums(pass, plan, side);
        for (index, light) in pass.lights.iter().enumerate() {
            self.light_factors(light, index);
            let side_light = &plan.lights[index];
            self.gl_power(pass, &plan.power);
            self.add_gl_terms(pass, side_light);
            let own = |m: usize| !(side == Side::Back && pass.models[m].front_for_back);
            let changing = |m: usize| side_light.models[m].is_some() && own(m);
            if !(1..pass.models.len()).any(changing) && !self.direct {
                continue;
            }
            self.variants(pass, light, side_light);
            for m in 1..pass.models.len() {
                if !own(m) {
                    continue;
                }
                match side_light.models[m] {
                    // In direct mode every term is the model's to add.
                    Some(change) if self.direct => {
                        let all = ModelLight {
                            ambient_term: true,
                            diffuse_term: true,
                            specular_term: true,
                            ..change
                        };
                        self.add_model_terms(pass, m, side_light, all)
                    }
                    Some(change) => self.add_model_terms(pass, m, side_light, change),
                    None if self.direct => self.add_model_terms(pass, m, side_light, GL_TERMS),
                    None => {}
                }
            }
        }
        self.finish(pass, plan, side);
    }

    /// GL's sums start at `e_cm + a_cm·a_cs`; each model's differences at 0.
    #[inline(always)]
    fn start_sums(&mut self, pass: &Pass<A>, plan: &SidePlan<A>, side: Side) {
        let zero = A::F::zero();
        for c in 0..3 {
            self.primary[c] = [plan.base[c]; BLOCK];
            self.secondary[c] = [zero; BLOCK];
        }
        self.alpha_sum = [plan.base[3]; BLOCK];
        self.largest_term = [zero; BLOCK];
        for m in 1..pass.models.len() {
            if (plan.model_touches[m] || self.direct)
                && !(side == Side::Back && pass.models[m].front_for_back)
            {
                // Only the sums the models add to: the secondary ones
                // where the specular colour is separate, alpha where summed.
                let delta = &mut self.deltas[m];
                for c in 0..3 {
                    delta[c] = [zero; BLOCK];
                }
                if pass.separate {
                    for c in 3..6 {
                        delta[c] = [zero; BLOCK];
                    }
                }
                if pass.alpha_sums {
                    delta[6] = [zero; BLOCK];
                }
            }
        }
    }

    /// `VP_pli`, the attenuation, GL's spot factor and `n·VP_pli` of one
    /// light.
    #[inline(always)]
    fn light_factors(&mut self, light: &plan::LightPlan<A>, index: usize) {
        let zero = A::F::zero();
        let one = A::F::one();
        self.directional = matches!(light.source, Source::Directional(_));
        match light.source {
            Source::Directional(vp) => {
                for axis in 0..3 {
                    self.vp[axis] = [vp[axis]; BLOCK];
                }
                self.att = [one; BLOCK];
            }
            Source::Positional {
                p,
                k,
                attenuated,
                clamp,
            } => {
                for axis in 0..3 {
                    for i in 0..BLOCK {
                        self.vp[axis][i] = p[axis] - self.p[axis][i];
                    }
                }
                normalize_lanes(&mut self.vp, &mut self.distance);
                if attenuated {
                    let cap = A::F::max_attenuation();
                    let most = if clamp { one } else { cap };
                    for i in 0..BLOCK {
                        let d = self.distance[i];
                        // At d = 0 only k0 counts (an infinite k1 or k2
                        // times 0 would be NaN).
                        let terms = if d > zero {
                            k[1] * d + k[2] * d * d
                        } else {
                            zero
                        };
                        self.att[i] = (one / (k[0] + terms)).smaller(most);
                    }
                } else {
                    self.att = [one; BLOCK];
                }
            }
        }
        match &light.cone {
            None => self.spot = [light.spot; BLOCK],
            Some(cone) => {
                let s = cone.direction;
                for i in 0..BLOCK {
                    let to_vertex = [-self.vp[0][i], -self.vp[1][i], -self.vp[2][i]];
                    let dot = to_vertex[0] * s[0] + to_vertex[1] * s[1] + to_vertex[2] * s[2];
                    self.spot_cos[i] = dot.larger(zero);
                    (self.spot_sin2[i], self.spot_stored[i]) =
                        A::store_cosine_of_unit(to_vertex, s, cone.inverse_direction2);
                }
                spot_power::<A>(
                    cone.power,
                    &self.spot_sin2,
                    &self.spot_stored,
                    &mut self.spot_power,
                );
                for i in 0..BLOCK {
                    self.spot[i] = if self.spot_cos[i] >= cone.cos_cutoff {
                        self.spot_power[i]
                    } else {
                        zero
                    };
                }
            }
        }
        if let Some(masks) = &self.masks {
            for i in 0..BLOCK {
                self.visible[i] = if (masks[i] >> index) & 1 == 1 {
                    one
                } else {
                    zero
                };
            }
        } else {
            self.visible = [one; BLOCK];
        }
        for i in 0..BLOCK {
            let n_dot_vp = self.n[0][i] * self.vp[0][i]
                + self.n[1][i] * self.vp[1][i]
                + self.n[2][i] * self.vp[2][i];
            self.n_dot_vp[i] = n_dot_vp;
            self.lit[i] = n_dot_vp.larger(zero);
            self.diffuse_base[i] = self.lit[i] * self.visible[i];
            // f_i: no specular where the light does not reach the front.
            self.gate[i] = if n_dot_vp > zero {
                self.visible[i]
            } else {
                zero
            };
        }
    }

    /// GL's specular power.
    #[inline(always)]
    fn gl_power(&mut self, pass: &Pass<A>, power: &PowerPlan<A>) {
        let mut out = [A::F::zero(); BLOCK];
        self.specular_power(pass, power, &mut out);
        self.power = out;
    }

    /// GL's terms of one light, into GL's sums: `sa·A + sd·D + ss·S`.
    #[inline(always)]
    fn add_gl_terms(&mut self, pass: &Pass<A>, light: &plan::SideLight<A>) {
        for i in 0..BLOCK {
            let scale = self.att[i] * self.spot[i];
            self.sa[i] = scale;
            self.sd[i] = scale * self.diffuse_base[i];
            self.ss[i] = scale * self.gate[i] * self.power[i];
        }
        for c in 0..3 {
            for i in 0..BLOCK {
                self.primary[c][i] += self.sa[i] * light.ambient[c] + self.sd[i] * light.diffuse[c];
            }
            let specular = if pass.separate {
                &mut self.secondary[c]
            } else {
                &mut self.primary[c]
            };
            for i in 0..BLOCK {
                specular[i] += self.ss[i] * light.specular[c];
            }
        }
        let [ambient, diffuse, specular] = light.magnitudes;
        for i in 0..BLOCK {
            let term = self.sa[i].abs() * ambient
                + self.sd[i].abs() * diffuse
                + self.ss[i].abs() * specular;
            self.largest_term[i] = self.largest_term[i].larger(term);
        }
        if pass.alpha_sums {
            for i in 0..BLOCK {
                self.alpha_sum[i] += self.sa[i] * light.ambient[3]
                    + self.sd[i] * light.diffuse[3]
                    + self.ss[i] * light.specular[3];
            }
        }
    }

    /// The variants of this light's factors that the models read.
    #[inline(always)]
    fn variants(&mut self, pass: &Pass<A>, light: &plan::LightPlan<A>, side: &plan::SideLight<A>) {
        let zero = A::F::zero();
        for (v, variant) in light.spot_variants.iter().enumerate() {
            let mut out = [zero; BLOCK];
            match *variant {
                SpotVariant::Constant(x) => out = [x; BLOCK],
                SpotVariant::Cone { cos_cutoff, power } => {
                    let gl_power = light.cone.as_ref().is_some_and(|c| c.power == power);
                    let mut powers = [zero; BLOCK];
                    let powers = if gl_power {
                        &self.spot_power
                    } else {
                        spot_power::<A>(power, &self.spot_sin2, &self.spot_stored, &mut powers);
                        &powers
                    };
                    for i in 0..BLOCK {
                        out[i] = if self.spot_cos[i] >= cos_cutoff {
                            powers[i]
                        } else {
                            zero
                        };
                    }
                }
            }
            self.spot_variants[v] = out;
        }
        for (v, key) in side.diffuse_variants.iter().enumerate() {
            let DiffuseKey { unclamped, raw } = *key;
            let mut out = [zero; BLOCK];
            let base = if unclamped { &self.n_dot_vp } else { &self.lit };
            let length = if raw { &self.length } else { &self.ones };
            for i in 0..BLOCK {
                out[i] = length[i] * base[i] * self.visible[i];
            }
            self.diffuse_variants[v] = out;
        }
        for (v, power) in side.power_variants.iter().enumerate() {
            let mut out = [zero; BLOCK];
            self.specular_power(pass, power, &mut out);
            self.power_variants[v] = out;
        }
    }

    /// The specular power `(base)^s` of every lane, the base as `power`'s
    /// key says: `n⊙ĥ` or `r⊙VP_e`, for GL's viewer or the other one, `ĥ`
    /// normalised or not, the normal's own length or not.
    #[inline(always)]
    fn specular_power(&mut self, pass: &Pass<A>, power: &PowerPlan<A>, out: &mut Lanes<A::F>) {
        let key = power.key;
        let blinn = power.specular_model == SpecularModel::BlinnPhong;
        // Below the cap by more than the tiers' error of a power.
        let uncapped = |lengths: &Lanes<A::F>| {
            let longest = lengths.iter().fold(A::F::zero(), |m, &l| m.larger(l));
            A::pow(longest, power.exponent) < A::F::of(0.99 * MAX_POWER)
        };
        if blinn && key.raw && uncapped(&self.length) {
            // (|n|·x)^s = |n|^s · x^s: the power of the unit normal's base,
            // times one power per vertex rather than one per light. (Where
            // |n|^s alone would reach the cap, the power is of the product.)
            let unit = PowerPlan {
                key: plan::PowerKey { raw: false, ..key },
                ..*power
            };
            if unit.key == plan::PowerKey::GL {
                *out = self.power;
            } else {
                self.unit_specular_power(pass, &unit, out);
            }
            if !power.zero_power_zero {
                let lengths = self.length_power(power.exponent);
                let cap = A::F::of(MAX_POWER);
                for i in 0..BLOCK {
                    out[i] = (out[i] * lengths[i]).smaller(cap);
                }
            }
            return;
        }
        self.unit_specular_power(pass, power, out);
    }

    /// [`Block::specular_power`] of the normal in the lanes (of unit length
    /// where the scene normalises, else as given) unless `power`'s key says
    /// raw: the body of the power of every key, apart so that it inlines.
    #[inline(always)]
    fn unit_specular_power(&mut self, pass: &Pass<A>, power: &PowerPlan<A>, out: &mut Lanes<A::F>) {
        // Each step is a loop of its own, without a branch on the scene: the
        // loops vectorise only so.
        let zero = A::F::zero();
        let one = A::F::one();
        let key = power.key;
        let blinn = power.specular_model == SpecularModel::BlinnPhong;
        let viewer = if key.swapped_viewer {
            pass.swapped_viewer
                .expect("a model that swaps the viewer has its viewer")
        } else {
            pass.viewer
        };
        let vp_e = match viewer {
            ViewerPlan::Local(_) if key.swapped_viewer => self.vp_e_swapped,
            ViewerPlan::Local(_) => self.vp_e,
            ViewerPlan::Infinite(d) => d.map(|x| [x; BLOCK]),
        };
        let dot = |a: &[Lanes<A::F>; 3], b: &[Lanes<A::F>; 3], i: usize| {
            a[0][i] * b[0][i] + a[1][i] * b[1][i] + a[2][i] * b[2][i]
        };
        // The base is the cosine of `a` and `b`, or their dot product.
        let (a, b) = if blinn {
            let mut h = [[zero; BLOCK]; 3];
            for axis in 0..3 {
                for i in 0..BLOCK {
                    h[axis][i] = self.vp[axis][i] + vp_e[axis][i];
                }
            }
            (self.n, h)
        } else {
            // r = 2(n·VP)n − VP, with the normal's own length where raw.
            let mut length2 = [one; BLOCK];
            if key.raw {
                for i in 0..BLOCK {
                    length2[i] = self.length[i] * self.length[i];
                }
            }
            let mut r = [[zero; BLOCK]; 3];
            for i in 0..BLOCK {
                let twice = (length2[i] + length2[i]) * dot(&self.n, &self.vp, i);
                for axis in 0..3 {
                    r[axis][i] = twice * self.n[axis][i] - self.vp[axis][i];
                }
            }
            (r, vp_e)
        };
        if pass.normalize && !key.raw && !key.half_unnormalized {
            // `a` is a unit vector (the normal, or `r` of unit vectors), and
            // so is `b` for Phong (`VP_e`); Blinn's `ĥ` is not.
            let mut inverse_b2 = [one; BLOCK];
            if blinn {
                let fixed = self.directional && matches!(viewer, ViewerPlan::Infinite(_));
                let lanes = if fixed { 1 } else { BLOCK };
                for i in 0..lanes {
                    let h2 = dot(&b, &b, i);
                    inverse_b2[i] = if h2 > zero { one / h2 } else { zero };
                }
                if fixed {
                    inverse_b2 = [inverse_b2[0]; BLOCK];
                }
            }
            for i in 0..BLOCK {
                (self.sin2[i], self.cos[i]) = A::store_cosine_of_unit(
                    [a[0][i], a[1][i], a[2][i]],
                    [b[0][i], b[1][i], b[2][i]],
                    inverse_b2[i],
                );
            }
            A::power_pass(power.plan, &self.sin2, &self.cos, out);
            if power.zero_power_zero {
                for i in 0..BLOCK {
                    out[i] = if A::positive(self.cos[i]) { one } else { zero };
                }
            }
            return;
        }
        for i in 0..BLOCK {
            self.base[i] = dot(&a, &b, i);
        }
        if blinn && !key.half_unnormalized {
            for i in 0..BLOCK {
                let h2 = dot(&b, &b, i);
                self.base[i] = if h2 > zero {
                    self.base[i] / h2.sqrt()
                } else {
                    zero
                };
            }
        }
        if blinn && key.raw {
            for i in 0..BLOCK {
                self.base[i] = self.base[i] * self.length[i];
            }
        }
        if power.zero_power_zero {
            for i in 0..BLOCK {
                out[i] = if self.base[i] > zero { one } else { zero };
            }
        } else {
            for i in 0..BLOCK {
                out[i] = A::pow(self.base[i], power.exponent);
            }
        }
    }

    /// `|n|^s` of every lane, computed once per side and exponent.
    #[inline(always)]
    fn length_power(&mut self, s: A::F) -> &Lanes<A::F> {
        if self.length_power_of != Some(s) {
            for i in 0..BLOCK {
                self.length_power[i] = A::pow(self.length[i], s);
            }
            self.length_power_of = Some(s);
        }
        &self.length_power
    }

    /// The differences model `m` makes to one light's terms (in direct
    /// mode, its terms).
    #[inline(always)]
    fn add_model_terms(
        &mut self,
        pass: &Pass<A>,
        m: usize,
        light: &plan::SideLight<A>,
        change: ModelLight,
    ) {
        let zero = A::F::zero();
        let att = if change.attenuation_one {
            &self.ones
        } else {
            &self.att
        };
        let spot = change.spot.map_or(&self.spot, |v| &self.spot_variants[v]);
        let ambient_spot = if change.ambient_unspotted {
            &self.ones
        } else {
            spot
        };
        let keep_ambient = if change.ambient_off {
            zero
        } else {
            A::F::one()
        };
        let diffuse = change
            .diffuse
            .map_or(&self.diffuse_base, |v| &self.diffuse_variants[v]);
        let gate = if change.ungated {
            &self.visible
        } else {
            &self.gate
        };
        let power = change
            .power
            .map_or(&self.power, |v| &self.power_variants[v]);
        let alpha = pass.models[m].alpha_summed;
        // In direct mode the model sums its own terms, not differences.
        let (gl_sa, gl_sd, gl_ss) = if self.direct {
            (&[zero; BLOCK], &[zero; BLOCK], &[zero; BLOCK])
        } else {
            (&self.sa, &self.sd, &self.ss)
        };
        let delta = &mut self.deltas[m];
        let mut add = |x: &Lanes<A::F>, product: &plan::Rgba<A::F>, first: usize| {
            for c in 0..3 {
                for i in 0..BLOCK {
                    delta[first + c][i] += x[i] * product[c];
                }
            }
            if alpha {
                for i in 0..BLOCK {
                    delta[6][i] += x[i] * product[3];
                }
            }
        };
        let mut x = [zero; BLOCK];
        if change.ambient_term {
            for i in 0..BLOCK {
                x[i] = keep_ambient * att[i] * ambient_spot[i] - gl_sa[i];
            }
            add(&x, &light.ambient, 0);
        }
        if change.diffuse_term {
            for i in 0..BLOCK {
                x[i] = att[i] * spot[i] * diffuse[i] - gl_sd[i];
            }
            add(&x, &light.diffuse, 0);
        }
        if change.specular_term {
            for i in 0..BLOCK {
                x[i] = att[i] * spot[i] * gate[i] * power[i] - gl_ss[i];
            }
            add(&x, &light.specular, if pass.separate { 3 } else { 0 });
        }
    }

    /// Every model's colour: its sums, clamped and written as the model
    /// writes them.
    #[inline(always)]
    fn finish(&mut self, pass: &Pass<A>, plan: &SidePlan<A>, side: Side) {
        let zero = A::F::zero();
        for (m, model) in pass.models.iter().enumerate() {
            if side == Side::Back && model.front_for_back {
                self.colors[m] = self.front[m];
                continue;
            }
            // What the model's differences are added to: GL's sums and the
            // difference of the bases, or, in direct mode, the model's base.
            let direct = self.direct && m > 0;
            let shift: [A::F; 4] = if direct {
                plan.model_bases[m]
            } else {
                std::array::from_fn(|c| plan.model_bases[m][c] - plan.base[c])
            };
            let touches = m > 0 && (plan.model_touches[m] || direct);
            let delta = &self.deltas[m];
            let out = &mut self.colors[m];
            for c in 0..3 {
                let color = &mut out[c];
                let from = if direct {
                    &[zero; BLOCK]
                } else {
                    &self.primary[c]
                };
                if touches {
                    for i in 0..BLOCK {
                        color[i] = from[i] + shift[c] + delta[c][i];
                    }
                } else {
                    for i in 0..BLOCK {
                        color[i] = from[i] + shift[c];
                    }
                }
                let mut secondary = [zero; BLOCK];
                if pass.separate {
                    if !direct {
                        secondary = self.secondary[c];
                    }
                    if touches {
                        for i in 0..BLOCK {
                            secondary[i] += delta[3 + c][i];
                        }
                    }
                }
                if !model.clamp {
                    for i in 0..BLOCK {
                        color[i] += secondary[i];
                    }
                } else if model.separate {
                    for i in 0..BLOCK {
                        color[i] =
                            (color[i].unit_clamped() + secondary[i].unit_clamped()).unit_clamped();
                    }
                } else {
                    for i in 0..BLOCK {
                        color[i] = (color[i] + secondary[i]).unit_clamped();
                    }
                }
                if model.srgb {
                    for i in 0..BLOCK {
                        color[i] = srgb_encode::<A>(color[i]);
                    }
                }
            }
            let alpha = &mut out[3];
            if model.alpha_summed {
                let from = if direct {
                    &[zero; BLOCK]
                } else {
                    &self.alpha_sum
                };
                for i in 0..BLOCK {
                    let d = if touches { delta[6][i] } else { zero };
                    let a = from[i] + shift[3] + d;
                    alpha[i] = if model.clamp { a.unit_clamped() } else { a };
                }
            } else {
                *alpha = [if model.clamp {
                    plan.alpha
                } else {
                    plan.raw_alpha
                }; BLOCK];
            }
            if side == Side::Front && model.front_for_back {
                self.front[m] = *out;
            }
        }
    }
}

/// The power of each lane's stored spot cosine.
#[inline(always)]
fn spot_power<A: Arith>(
    power: SpotPower<A>,
    sin2: &Lanes<A::F>,
    stored: &Lanes<A::F>,
    out: &mut Lanes<A::F>,
) {
    match power {
        SpotPower::Plan(plan) => A::power_pass(plan, sin2, stored, out),
        SpotPower::Positive => {
            for i in 0..BLOCK {
                out[i] = if A::positive(stored[i]) {
                    A::F::one()
                } else {
                    A::F::zero()
                };
            }
        }
    }
}

/// The sRGB transfer curve in the tier's arithmetic (see
/// `glint_lighting::deviation::srgb_encode`).
#[inline(always)]
fn srgb_encode<A: Arith>(c: A::F) -> A::F {
    let linear = A::F::of(12.92) * c;
    let curve = A::F::of(1.055) * A::pow(c, A::F::of(1.0 / 2.4)) - A::F::of(0.055);
    if c <= A::F::of(0.003_130_8) {
        linear
    } else {
        curve
    }
}

/// Each lane's vector `v` to unit length (zero stays zero), and its length
/// into `length`. Lengths whose square leaves the type's safe range are
/// taken by scaling by the largest component first.
#[inline(always)]
fn normalize_lanes<F: Real>(v: &mut [Lanes<F>; 3], length: &mut Lanes<F>) {
    let mut out_of_range = 0u32;
    for i in 0..BLOCK {
        let d2 = v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i];
        length[i] = d2;
        let inside = d2 >= F::SAFE_DISTANCE2.start && d2 < F::SAFE_DISTANCE2.end;
        out_of_range += u32::from(!inside);
    }
    if out_of_range == 0 {
        for i in 0..BLOCK {
            let d = length[i].sqrt();
            let inverse = F::one() / d;
            for axis in v.iter_mut() {
                axis[i] = axis[i] * inverse;
            }
            length[i] = d;
        }
        return;
    }
    for i in 0..BLOCK {
        let largest = v[0][i].abs().max(v[1][i].abs()).max(v[2][i].abs());
        if !(largest > F::zero() && largest.is_finite()) {
            for axis in v.iter_mut() {
                axis[i] = F::zero();
            }
            length[i] = F::zero();
            continue;
        }
        let scaled = [v[0][i] / largest, v[1][i] / largest, v[2][i] / largest];
        let l = (scaled[0] * scaled[0] + scaled[1] * scaled[1] + scaled[2] * scaled[2]).sqrt();
        for axis in 0..3 {
            v[axis][i] = scaled[axis] / l;
        }
        length[i] = largest * l;
    }
}

#[cfg(test)]
pub(crate) mod tests;
