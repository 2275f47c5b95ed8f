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

pub(crate) mod arith;
pub(crate) mod dispatch;
pub(crate) mod plan;

use glam::DVec3;
use glint_lighting::{LightMask, MAX_RAW_NORMAL, Side, SpecularModel, unit_or_zero};

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
    /// The normals' own lengths, capped at [`MAX_RAW_NORMAL`]; empty where
    /// no model reads them.
    pub lengths: Vec<F>,
    /// Per point, which lights reach it (the renderer's shadows).
    pub visible: Option<Vec<LightMask>>,
}

impl<F: Real> Points<F> {
    /// The points at `positions` with `normals`, recentred on `centre`.
    pub fn new<A: Arith<F = F>>(
        pass: &Pass<A>,
        centre: DVec3,
        positions: &[DVec3],
        normals: &[DVec3],
    ) -> Self {
        let len = positions.len();
        let mut points = Points {
            len,
            ..Points::default()
        };
        if pass.positions {
            for axis in 0..3 {
                points.positions[axis] = positions
                    .iter()
                    .map(|p| F::of(p[axis] - centre[axis]))
                    .collect();
            }
        }
        let lanes: Vec<DVec3> = if pass.normalize {
            normals.iter().map(|&n| unit_or_zero(n)).collect()
        } else {
            normals.to_vec()
        };
        for axis in 0..3 {
            points.normals[axis] = lanes.iter().map(|n| F::of(n[axis])).collect();
        }
        if pass.raw_lengths {
            points.lengths = normals
                .iter()
                .map(|n| F::of(n.length().min(MAX_RAW_NORMAL)))
                .collect();
        }
        points
    }
}

/// Whether some normal of `normals` is not of unit length, so that a port
/// that does not normalise them draws something else than GL.
pub(crate) fn unnormalized(normals: &[DVec3]) -> bool {
    normals.iter().any(|n| (n.length() - 1.0).abs() > 1e-12)
}

/// `x` clamped to [0, 1].
#[inline(always)]
fn clamp01<F: Real>(x: F) -> F {
    x.max(F::zero()).min(F::one())
}

/// The working set of one block: its points, GL's sums, one light's
/// factors and variants, and each model's differences and colours.
pub(crate) struct Block<A: Arith> {
    /// Points in the block (the lanes past them repeat its last position,
    /// with a zero normal).
    pub len: usize,
    p: [Lanes<A::F>; 3],
    n: [Lanes<A::F>; 3],
    length: Lanes<A::F>,
    vp_e: [Lanes<A::F>; 3],
    vp_e_swapped: [Lanes<A::F>; 3],
    masks: Option<[LightMask; BLOCK]>,
    ones: Lanes<A::F>,
    // GL's sums, in f64 (see `deltas`).
    primary: [Lanes<f64>; 3],
    secondary: [Lanes<f64>; 3],
    alpha_sum: Lanes<f64>,
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
    spot_variants: Vec<Lanes<A::F>>,
    diffuse_variants: Vec<Lanes<A::F>>,
    power_variants: Vec<Lanes<A::F>>,
    /// Per model: the differences of its sums from GL's, primary RGB,
    /// secondary RGB, alpha. In f64, as GL's sums are: a model that takes
    /// away a term of GL's (the specular of `x^s` near its cap) must take
    /// away exactly what GL's sum holds, and the difference of two f32 and
    /// its product with an f32 are exact, or nearly, in f64.
    deltas: Vec<[Lanes<f64>; 7]>,
    /// Per model: its colour, RGBA.
    pub colors: Vec<[Lanes<A::F>; 4]>,
    /// Per model: its front colour, kept for a back side that takes it.
    front: Vec<[Lanes<A::F>; 4]>,
    /// The largest magnitude of a GL term of the block.
    largest_term: f64,
    /// Each model sums its own terms, rather than its differences from
    /// GL's (see [`Pass::direct_above`]).
    direct: bool,
}

impl<A: Arith> Block<A> {
    pub fn new(pass: &Pass<A>) -> Box<Self> {
        let zero = [A::F::zero(); BLOCK];
        let models = pass.models.len();
        let most = |count: &dyn Fn(&SidePlan<A>) -> usize| {
            pass.sides.iter().flatten().map(count).max().unwrap_or(0)
        };
        let spot_variants = pass
            .lights
            .iter()
            .map(|l| l.spot_variants.len())
            .max()
            .unwrap_or(0);
        let power_variants = most(&|s| {
            s.lights
                .iter()
                .map(|l| l.power_variants.len())
                .max()
                .unwrap_or(0)
        });
        let diffuse_variants = most(&|s| {
            s.lights
                .iter()
                .map(|l| l.diffuse_variants.len())
                .max()
                .unwrap_or(0)
        });
        Box::new(Self {
            len: 0,
            p: [zero; 3],
            n: [zero; 3],
            length: zero,
            vp_e: [zero; 3],
            vp_e_swapped: [zero; 3],
            masks: None,
            ones: [A::F::one(); BLOCK],
            primary: [[0.0; BLOCK]; 3],
            secondary: [[0.0; BLOCK]; 3],
            alpha_sum: [0.0; BLOCK],
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
            spot_variants: vec![zero; spot_variants],
            diffuse_variants: vec![zero; diffuse_variants],
            power_variants: vec![zero; power_variants],
            deltas: vec![[[0.0; BLOCK]; 7]; models],
            colors: vec![[zero; 4]; models],
            front: vec![[zero; 4]; models],
            largest_term: 0.0,
            direct: false,
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
        let sign = match side {
            Side::Front => A::F::one(),
            Side::Back => -A::F::one(),
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
        self.direct = false;
        self.evaluate_models(pass, plan, side);
        if pass.models.len() > 1 && self.largest_term > pass.direct_above {
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
        for c in 0..3 {
            self.primary[c] = [plan.base[c]; BLOCK];
            self.secondary[c] = [0.0; BLOCK];
        }
        self.alpha_sum = [plan.base[3]; BLOCK];
        self.largest_term = 0.0;
        for m in 1..pass.models.len() {
            if (plan.model_touches[m] || self.direct)
                && !(side == Side::Back && pass.models[m].front_for_back)
            {
                self.deltas[m] = [[0.0; BLOCK]; 7];
            }
        }
    }

    /// `VP_pli`, the attenuation, GL's spot factor and `n·VP_pli` of one
    /// light.
    #[inline(always)]
    fn light_factors(&mut self, light: &plan::LightPlan<A>, index: usize) {
        let zero = A::F::zero();
        let one = A::F::one();
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
                    for i in 0..BLOCK {
                        let d = self.distance[i];
                        // At d = 0 only k0 counts (an infinite k1 or k2
                        // times 0 would be NaN).
                        let terms = if d > zero {
                            k[1] * d + k[2] * d * d
                        } else {
                            zero
                        };
                        let att = (one / (k[0] + terms)).min(cap);
                        self.att[i] = if clamp { att.min(one) } else { att };
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
                    self.spot_cos[i] = dot.max(zero);
                    (self.spot_sin2[i], self.spot_stored[i]) = A::store_cosine(to_vertex, s);
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
            self.lit[i] = n_dot_vp.max(zero);
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
                self.primary[c][i] +=
                    self.sa[i].wide() * light.ambient[c] + self.sd[i].wide() * light.diffuse[c];
            }
            let specular = if pass.separate {
                &mut self.secondary[c]
            } else {
                &mut self.primary[c]
            };
            for i in 0..BLOCK {
                specular[i] += self.ss[i].wide() * light.specular[c];
            }
        }
        let [ambient, diffuse, specular] = light.magnitudes;
        let mut largest = 0.0f64;
        for i in 0..BLOCK {
            let term = self.sa[i].wide().abs() * ambient
                + self.sd[i].wide().abs() * diffuse
                + self.ss[i].wide().abs() * specular;
            largest = largest.max(term);
        }
        self.largest_term = self.largest_term.max(largest);
        if pass.alpha_sums {
            for i in 0..BLOCK {
                self.alpha_sum[i] += self.sa[i].wide() * light.ambient[3]
                    + self.sd[i].wide() * light.diffuse[3]
                    + self.ss[i].wide() * light.specular[3];
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
                    let mut powers = [zero; BLOCK];
                    spot_power::<A>(power, &self.spot_sin2, &self.spot_stored, &mut powers);
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
            for i in 0..BLOCK {
                let base = if unclamped {
                    self.n_dot_vp[i]
                } else {
                    self.lit[i]
                };
                let length = if raw { self.length[i] } else { A::F::one() };
                out[i] = length * base * self.visible[i];
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
        let zero = A::F::zero();
        let key = power.key;
        let (viewer, local) = if key.swapped_viewer {
            (
                pass.swapped_viewer
                    .expect("a model that swaps the viewer has its viewer"),
                &self.vp_e_swapped,
            )
        } else {
            (pass.viewer, &self.vp_e)
        };
        let eye = |i: usize| match viewer {
            ViewerPlan::Local(_) => [local[0][i], local[1][i], local[2][i]],
            ViewerPlan::Infinite(d) => d,
        };
        let dot = |a: [A::F; 3], b: [A::F; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let blinn = power.specular_model == SpecularModel::BlinnPhong;
        // A cosine of unit vectors, raised by the tier's plan; else a plain
        // power of the base.
        let of_cosine = pass.normalize && !key.raw && !key.half_unnormalized;
        for i in 0..BLOCK {
            let n = [self.n[0][i], self.n[1][i], self.n[2][i]];
            let vp = [self.vp[0][i], self.vp[1][i], self.vp[2][i]];
            let vp_e = eye(i);
            let (a, b) = if blinn {
                (n, [vp[0] + vp_e[0], vp[1] + vp_e[1], vp[2] + vp_e[2]])
            } else {
                // r = 2(n·VP)n − VP, with the normal's own length where raw.
                let n_dot_vp = dot(n, vp);
                let twice = if key.raw {
                    let l = self.length[i];
                    (l + l) * l * n_dot_vp
                } else {
                    n_dot_vp + n_dot_vp
                };
                (
                    [
                        twice * n[0] - vp[0],
                        twice * n[1] - vp[1],
                        twice * n[2] - vp[2],
                    ],
                    vp_e,
                )
            };
            if of_cosine {
                (self.sin2[i], self.cos[i]) = A::store_cosine(a, b);
            } else {
                let mut x = dot(a, b);
                if blinn && !key.half_unnormalized {
                    let h2 = dot(b, b);
                    x = if h2 > zero { x / h2.sqrt() } else { zero };
                }
                if blinn && key.raw {
                    x = x * self.length[i];
                }
                self.base[i] = x;
            }
        }
        if of_cosine {
            A::power_pass(power.plan, &self.sin2, &self.cos, out);
            if power.zero_power_zero {
                for i in 0..BLOCK {
                    out[i] = if A::positive(self.cos[i]) {
                        A::F::one()
                    } else {
                        zero
                    };
                }
            }
        } else {
            for i in 0..BLOCK {
                let x = self.base[i];
                out[i] = if power.zero_power_zero {
                    if x > zero { A::F::one() } else { zero }
                } else {
                    A::pow(x, power.exponent)
                };
            }
        }
    }

    /// The differences model `m` makes to one light's terms.
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
        let gl = if self.direct { 0.0 } else { 1.0 };
        let delta = &mut self.deltas[m];
        let mut add = |x: &Lanes<f64>, product: &plan::Rgba<f64>, first: usize| {
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
        let mut x = [0.0; BLOCK];
        if change.ambient_term {
            for i in 0..BLOCK {
                x[i] = (keep_ambient * att[i] * ambient_spot[i]).wide() - gl * self.sa[i].wide();
            }
            add(&x, &light.ambient, 0);
        }
        if change.diffuse_term {
            for i in 0..BLOCK {
                x[i] = (att[i] * spot[i] * diffuse[i]).wide() - gl * self.sd[i].wide();
            }
            add(&x, &light.diffuse, 0);
        }
        if change.specular_term {
            for i in 0..BLOCK {
                x[i] = (att[i] * spot[i] * gate[i] * power[i]).wide() - gl * self.ss[i].wide();
            }
            add(&x, &light.specular, if pass.separate { 3 } else { 0 });
        }
    }

    /// Every model's colour: its sums, clamped and written as the model
    /// writes them.
    #[inline(always)]
    fn finish(&mut self, pass: &Pass<A>, plan: &SidePlan<A>, side: Side) {
        for (m, model) in pass.models.iter().enumerate() {
            if side == Side::Back && model.front_for_back {
                self.colors[m] = self.front[m];
                continue;
            }
            const NONE: [Lanes<f64>; 3] = [[0.0; BLOCK]; 3];
            // What the model's differences are added to: GL's sums and the
            // difference of the bases, or, in direct mode, the model's base.
            let direct = self.direct && m > 0;
            let (primary, secondary, alpha_sum, shift) = if direct {
                (&NONE, &NONE, &NONE[0], plan.model_bases[m])
            } else {
                let shift = std::array::from_fn(|c| plan.model_bases[m][c] - plan.base[c]);
                (&self.primary, &self.secondary, &self.alpha_sum, shift)
            };
            let touches = m > 0 && (plan.model_touches[m] || direct);
            let delta = &self.deltas[m];
            let out = &mut self.colors[m];
            for c in 0..3 {
                for i in 0..BLOCK {
                    let (dp, ds) = if touches {
                        (delta[c][i], delta[3 + c][i])
                    } else {
                        (0.0, 0.0)
                    };
                    let p = primary[c][i] + shift[c] + dp;
                    let s = if pass.separate {
                        secondary[c][i] + ds
                    } else {
                        0.0
                    };
                    let color = A::F::of(if !model.clamp {
                        p + s
                    } else if model.separate {
                        clamp01(clamp01(p) + clamp01(s))
                    } else {
                        clamp01(p + s)
                    });
                    out[c][i] = if model.srgb {
                        srgb_encode::<A>(color)
                    } else {
                        color
                    };
                }
            }
            for i in 0..BLOCK {
                out[3][i] = if model.alpha_summed {
                    let dp = if touches { delta[6][i] } else { 0.0 };
                    let a = alpha_sum[i] + shift[3] + dp;
                    A::F::of(if model.clamp { clamp01(a) } else { a })
                } else if model.clamp {
                    plan.alpha
                } else {
                    plan.raw_alpha
                };
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
    let mut out_of_range = false;
    for i in 0..BLOCK {
        let d2 = v[0][i] * v[0][i] + v[1][i] * v[1][i] + v[2][i] * v[2][i];
        length[i] = d2;
        out_of_range |= !F::SAFE_DISTANCE2.contains(&d2);
    }
    if !out_of_range {
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
