//! The explanation of a colour: each term of the lighting equation before
//! clamping, and statistics of the terms over a batch.

use glam::{DVec3, DVec4};

use super::ColorControl;

/// One light's contribution to a vertex colour (RGB, before clamping). The
/// colour terms already include `attenuation · spot`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightTerms {
    pub ambient: DVec3,
    pub diffuse: DVec3,
    pub specular: DVec3,
    pub attenuation: f64,
    pub spot: f64,
}

/// Every term of one side of one vertex, before clamping.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Breakdown {
    /// `e_cm`
    pub emission: DVec3,
    /// `a_cm · a_cs`
    pub global_ambient: DVec3,
    pub lights: Vec<LightTerms>,
}

impl Breakdown {
    /// The primary colour: everything but the specular terms.
    pub fn primary(&self) -> DVec3 {
        self.lights
            .iter()
            .fold(self.emission + self.global_ambient, |sum, l| {
                sum + l.ambient + l.diffuse
            })
    }

    /// The secondary colour: the sum of the specular terms.
    pub fn secondary(&self) -> DVec3 {
        self.lights.iter().map(|l| l.specular).sum()
    }

    /// The colour before any clamping.
    pub fn unclamped(&self) -> DVec3 {
        self.primary() + self.secondary()
    }

    /// The colour GL writes: with a single colour, the sum clamped to [0, 1];
    /// with a separate specular colour, primary and secondary each clamped,
    /// then summed and clamped again. Alpha is the diffuse material's.
    pub fn color(&self, control: ColorControl, diffuse_alpha: f64) -> DVec4 {
        let rgb = match control {
            ColorControl::Single => self.unclamped(),
            ColorControl::SeparateSpecular => clamp01(self.primary()) + clamp01(self.secondary()),
        };
        clamp01(rgb).extend(diffuse_alpha.clamp(0.0, 1.0))
    }

    /// Whether clamping changed this colour: some channel of the unclamped sum
    /// lies outside [0, 1].
    pub fn was_clamped(&self) -> bool {
        let c = self.unclamped();
        c.min_element() < 0.0 || c.max_element() > 1.0
    }
}

fn clamp01(c: DVec3) -> DVec3 {
    c.clamp(DVec3::ZERO, DVec3::ONE)
}

/// Mean and maximum of one RGB term over a batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorStat {
    pub mean: DVec3,
    pub max: DVec3,
}

/// Mean and maximum of one scalar factor over a batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FactorStat {
    pub mean: f64,
    pub max: f64,
}

/// Statistics of one light's terms over a batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSummary {
    pub ambient: ColorStat,
    pub diffuse: ColorStat,
    pub specular: ColorStat,
    pub attenuation: FactorStat,
    pub spot: FactorStat,
}

/// Statistics of every term over a batch of breakdowns.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub count: usize,
    pub emission: ColorStat,
    pub global_ambient: ColorStat,
    pub lights: Vec<LightSummary>,
    /// The share of breakdowns whose sum was clamped.
    pub clamped_share: f64,
}

impl Summary {
    /// Summarises `breakdowns`, which all come from one lighting description
    /// (so they have the same number of lights). `None` for an empty batch.
    pub fn of<'a>(breakdowns: impl IntoIterator<Item = &'a Breakdown>) -> Option<Summary> {
        let mut acc: Option<Accumulator> = None;
        for b in breakdowns {
            acc.get_or_insert_with(|| Accumulator::new(b.lights.len()))
                .add(b);
        }
        acc.map(Accumulator::finish)
    }
}

/// Running sums and maxima; kept apart from [`Summary`] so that a summary is
/// always complete.
struct Accumulator {
    count: usize,
    clamped: usize,
    emission: ColorAcc,
    global_ambient: ColorAcc,
    lights: Vec<[ColorAcc; 3]>,
    factors: Vec<[FactorAcc; 2]>,
}

#[derive(Clone, Copy)]
struct ColorAcc {
    sum: DVec3,
    max: DVec3,
}

impl ColorAcc {
    const EMPTY: Self = Self {
        sum: DVec3::ZERO,
        max: DVec3::NEG_INFINITY,
    };

    fn add(&mut self, c: DVec3) {
        self.sum += c;
        self.max = self.max.max(c);
    }

    fn finish(self, count: usize) -> ColorStat {
        ColorStat {
            mean: self.sum / count as f64,
            max: self.max,
        }
    }
}

#[derive(Clone, Copy)]
struct FactorAcc {
    sum: f64,
    max: f64,
}

impl FactorAcc {
    const EMPTY: Self = Self {
        sum: 0.0,
        max: f64::NEG_INFINITY,
    };

    fn add(&mut self, x: f64) {
        self.sum += x;
        self.max = self.max.max(x);
    }

    fn finish(self, count: usize) -> FactorStat {
        FactorStat {
            mean: self.sum / count as f64,
            max: self.max,
        }
    }
}

impl Accumulator {
    fn new(lights: usize) -> Self {
        Self {
            count: 0,
            clamped: 0,
            emission: ColorAcc::EMPTY,
            global_ambient: ColorAcc::EMPTY,
            lights: vec![[ColorAcc::EMPTY; 3]; lights],
            factors: vec![[FactorAcc::EMPTY; 2]; lights],
        }
    }

    fn add(&mut self, b: &Breakdown) {
        self.count += 1;
        self.clamped += usize::from(b.was_clamped());
        self.emission.add(b.emission);
        self.global_ambient.add(b.global_ambient);
        for ((colors, factors), l) in self.lights.iter_mut().zip(&mut self.factors).zip(&b.lights) {
            colors[0].add(l.ambient);
            colors[1].add(l.diffuse);
            colors[2].add(l.specular);
            factors[0].add(l.attenuation);
            factors[1].add(l.spot);
        }
    }

    fn finish(self) -> Summary {
        let n = self.count;
        Summary {
            count: n,
            emission: self.emission.finish(n),
            global_ambient: self.global_ambient.finish(n),
            lights: self
                .lights
                .iter()
                .zip(&self.factors)
                .map(|([a, d, s], [att, spot])| LightSummary {
                    ambient: a.finish(n),
                    diffuse: d.finish(n),
                    specular: s.finish(n),
                    attenuation: att.finish(n),
                    spot: spot.finish(n),
                })
                .collect(),
            clamped_share: self.clamped as f64 / n as f64,
        }
    }
}
