//! Evaluating a validated `/v1/shade` request into its response body: the
//! evaluator of the requested precision for the colours, the reference
//! evaluator for the term breakdown when one is asked for.
//!
//! The breakdown always comes from the reference evaluator, whatever the
//! precision: it explains the ground truth, and the colours of an f32 tier
//! differ from its sum by at most that tier's documented bound.

use std::time::Instant;

use glam::{DVec3, DVec4, Vec4};
use rayon::prelude::*;
use serde::Serialize;

use crate::lighting::kernel::{Colors, Kernel, Tier};
use crate::lighting::reference::{self, Side};
use crate::lighting::terms::{Breakdown, ColorStat, FactorStat, LightTerms, Summary};
use crate::lighting::{LightPosition, Lighting};
use crate::scene::{Precision, ShadeScene, TermsDetail};

/// The `200` body of `/v1/shade`.
#[derive(Debug, Serialize)]
pub struct ShadeResponse {
    /// RGBA, serialised as arrays of four numbers.
    pub colors: Vec<Vec4>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub back_colors: Option<Vec<Vec4>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub terms: Option<TermsOut>,
    pub modeled: Vec<Term>,
    pub precision: PrecisionOut,
    pub stats: Stats,
    pub warnings: Vec<Warning>,
}

#[derive(Debug, Serialize)]
pub struct PrecisionOut {
    pub mode: Precision,
    pub max_abs_error: f64,
}

impl From<Precision> for PrecisionOut {
    fn from(mode: Precision) -> Self {
        Self {
            mode,
            max_abs_error: mode.max_abs_error(),
        }
    }
}

#[derive(Debug, Serialize)]
pub struct Stats {
    pub vertices: usize,
    pub lights: usize,
    pub compute_ms: f64,
}

/// Something the client should know about its answer; never a silent change.
#[derive(Debug, Serialize)]
pub struct Warning {
    pub code: &'static str,
    pub count: usize,
    pub detail: String,
}

/// The breakdown of one side.
#[derive(Debug, Serialize)]
pub struct SideTerms {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub summary: Option<SummaryOut>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_vertex: Option<Vec<BreakdownOut>>,
}

/// `terms`: the front side's breakdown, and the back side's when two-sided.
#[derive(Debug, Serialize)]
pub struct TermsOut {
    #[serde(flatten)]
    pub front: SideTerms,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub back: Option<SideTerms>,
}

#[derive(Debug, Serialize)]
pub struct BreakdownOut {
    pub emission: [f64; 3],
    pub global_ambient: [f64; 3],
    pub lights: Vec<LightTermsOut>,
    /// The sum of the terms, before clamping.
    pub unclamped: [f64; 3],
}

#[derive(Debug, Serialize)]
pub struct LightTermsOut {
    pub ambient: [f64; 3],
    pub diffuse: [f64; 3],
    pub specular: [f64; 3],
    pub attenuation: f64,
    pub spot: f64,
}

impl From<&Breakdown> for BreakdownOut {
    fn from(b: &Breakdown) -> Self {
        Self {
            emission: b.emission.to_array(),
            global_ambient: b.global_ambient.to_array(),
            lights: b.lights.iter().map(LightTermsOut::from).collect(),
            unclamped: b.unclamped().to_array(),
        }
    }
}

impl From<&LightTerms> for LightTermsOut {
    fn from(l: &LightTerms) -> Self {
        Self {
            ambient: l.ambient.to_array(),
            diffuse: l.diffuse.to_array(),
            specular: l.specular.to_array(),
            attenuation: l.attenuation,
            spot: l.spot,
        }
    }
}

#[derive(Debug, Serialize)]
pub struct SummaryOut {
    pub vertices: usize,
    pub clamped_share: f64,
    pub emission: ColorStatOut,
    pub global_ambient: ColorStatOut,
    pub lights: Vec<LightSummaryOut>,
}

#[derive(Debug, Serialize)]
pub struct ColorStatOut {
    pub mean: [f64; 3],
    pub max: [f64; 3],
}

#[derive(Debug, Serialize)]
pub struct FactorStatOut {
    pub mean: f64,
    pub max: f64,
}

#[derive(Debug, Serialize)]
pub struct LightSummaryOut {
    pub ambient: ColorStatOut,
    pub diffuse: ColorStatOut,
    pub specular: ColorStatOut,
    pub attenuation: FactorStatOut,
    pub spot: FactorStatOut,
}

impl From<ColorStat> for ColorStatOut {
    fn from(s: ColorStat) -> Self {
        Self {
            mean: s.mean.to_array(),
            max: s.max.to_array(),
        }
    }
}

impl From<FactorStat> for FactorStatOut {
    fn from(s: FactorStat) -> Self {
        Self {
            mean: s.mean,
            max: s.max,
        }
    }
}

impl From<Summary> for SummaryOut {
    fn from(s: Summary) -> Self {
        Self {
            vertices: s.count,
            clamped_share: s.clamped_share,
            emission: s.emission.into(),
            global_ambient: s.global_ambient.into(),
            lights: s
                .lights
                .into_iter()
                .map(|l| LightSummaryOut {
                    ambient: l.ambient.into(),
                    diffuse: l.diffuse.into(),
                    specular: l.specular.into(),
                    attenuation: l.attenuation.into(),
                    spot: l.spot.into(),
                })
                .collect(),
        }
    }
}

/// Evaluates `scene` on the current rayon pool.
pub fn shade(scene: &ShadeScene) -> ShadeResponse {
    let started = Instant::now();
    let lighting = &scene.lighting;
    let colors = match scene.precision {
        Precision::Reference => reference_colors(scene),
        Precision::Accurate => kernel_colors(scene, Tier::Accurate),
        Precision::Fast => kernel_colors(scene, Tier::Fast),
    };
    let terms = match scene.terms {
        TermsDetail::None => None,
        detail => Some(TermsOut {
            front: side_terms(scene, Side::Front, detail),
            back: lighting
                .model
                .two_side
                .then(|| side_terms(scene, Side::Back, detail)),
        }),
    };
    let mut warnings = Vec::new();
    if scene.zero_normals > 0 {
        warnings.push(Warning {
            code: "zero_normals",
            count: scene.zero_normals,
            detail: format!(
                "{} normals have zero length; they get no diffuse or specular light",
                scene.zero_normals
            ),
        });
    }
    warnings.extend(precision_warnings(scene));
    ShadeResponse {
        colors: colors.front,
        back_colors: colors.back,
        terms,
        modeled: modeled(lighting),
        precision: scene.precision.into(),
        stats: Stats {
            vertices: scene.positions.len(),
            lights: lighting.lights.len(),
            compute_ms: started.elapsed().as_secs_f64() * 1e3,
        },
        warnings,
    }
}

/// The largest shininess for which the f32 tiers keep their documented
/// bounds when normals are used as given. With unit normals the specular
/// base is a cosine, evaluated without losing the digits near 1, and the
/// bounds hold at any shininess; a raw normal's `n·ĥ` is a plain f32 whose
/// relative error, about 1e-7, the power multiplies by the shininess.
pub const MAX_BOUNDED_RAW_SHININESS: f64 = 64.0;

/// Why an f32 tier cannot promise its bound under `lighting`, a sentence
/// per reason; none when it can. Its errors are relative to the size of the
/// terms, and the bound absolute. Without negative colours no term is below
/// zero, so a term larger than 1 saturates the clamped colour and its
/// rounding never shows; negative colours let large terms cancel to a small
/// colour that keeps their error.
pub fn precision_bound_reasons(lighting: &Lighting) -> Vec<String> {
    let mut reasons = Vec::new();
    let colours = [lighting.model.ambient]
        .into_iter()
        .chain(
            [&lighting.front, &lighting.back]
                .into_iter()
                .flat_map(|m| [m.ambient, m.diffuse, m.specular, m.emission]),
        )
        .chain(
            lighting
                .lights
                .iter()
                .flat_map(|l| [l.ambient, l.diffuse, l.specular]),
        );
    if colours
        .into_iter()
        .any(|c| c.truncate().min_element() < 0.0)
    {
        reasons.push(
            "negative colours let large terms cancel: where they do, the error of this \
             precision is its bound times the size of the largest term; `reference` is exact"
                .to_owned(),
        );
    }
    let shininess = lighting.front.shininess.max(lighting.back.shininess);
    if !lighting.model.normalize_normals && shininess > MAX_BOUNDED_RAW_SHININESS {
        reasons.push(format!(
            "a shininess of {shininess} with normalize_normals off: above \
             {MAX_BOUNDED_RAW_SHININESS}, f32 cannot hold the documented bound of this \
             precision near highlights; `reference` is exact"
        ));
    }
    reasons
}

/// [`precision_bound_reasons`] as warnings about every vertex.
fn precision_warnings(scene: &ShadeScene) -> Vec<Warning> {
    if scene.precision == Precision::Reference || scene.positions.is_empty() {
        return Vec::new();
    }
    precision_bound_reasons(&scene.lighting)
        .into_iter()
        .map(|detail| Warning {
            code: "precision_bound",
            count: scene.positions.len(),
            detail,
        })
        .collect()
}

fn kernel_colors(scene: &ShadeScene, tier: Tier) -> Colors {
    let kernel = Kernel::new(&scene.lighting, &scene.positions);
    kernel.shade(tier, &kernel.prepare(&scene.positions, &scene.normals))
}

/// Batches up to this many vertices are evaluated on the calling thread:
/// handing them to the pool costs more than they do.
const SEQUENTIAL_VERTICES: usize = 4096;

/// `f` of every vertex (position, normal), in parallel on the current rayon
/// pool for batches worth it.
fn map_vertices<T: Send>(scene: &ShadeScene, f: impl Fn(DVec3, DVec3) -> T + Sync) -> Vec<T> {
    if scene.positions.len() <= SEQUENTIAL_VERTICES {
        let pairs = scene.positions.iter().zip(&scene.normals);
        pairs.map(|(&p, &n)| f(p, n)).collect()
    } else {
        scene
            .positions
            .par_iter()
            .zip(&scene.normals)
            .map(|(&p, &n)| f(p, n))
            .collect()
    }
}

fn reference_colors(scene: &ShadeScene) -> Colors {
    let side = |side: Side| -> Vec<Vec4> {
        map_vertices(scene, |p, n| {
            reference::color(&scene.lighting, side, p, n).as_vec4()
        })
    };
    Colors {
        front: side(Side::Front),
        back: scene.lighting.model.two_side.then(|| side(Side::Back)),
    }
}

fn side_terms(scene: &ShadeScene, side: Side, detail: TermsDetail) -> SideTerms {
    let breakdowns = map_vertices(scene, |p, n| {
        reference::evaluate(&scene.lighting, side, p, n)
    });
    SideTerms {
        summary: Summary::of(&breakdowns).map(SummaryOut::from),
        per_vertex: (detail == TermsDetail::PerVertex)
            .then(|| breakdowns.iter().map(BreakdownOut::from).collect()),
    }
}

/// A term of the lighting equation, as `modeled` names it: `emission`,
/// `global_ambient`, `lights[i].diffuse`. The order is that of the equation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Term {
    Emission,
    GlobalAmbient,
    Light(usize, LightTerm),
}

/// A term of one light's contribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum LightTerm {
    Ambient,
    Diffuse,
    Specular,
    Attenuation,
    Spot,
}

impl Term {
    /// The name, written into `buf` when it has a light's index.
    fn name<'b>(&self, buf: &'b mut [u8; 40]) -> &'b str {
        let (i, term) = match self {
            Term::Emission => return "emission",
            Term::GlobalAmbient => return "global_ambient",
            Term::Light(i, term) => (*i, term),
        };
        let term = match term {
            LightTerm::Ambient => "ambient",
            LightTerm::Diffuse => "diffuse",
            LightTerm::Specular => "specular",
            LightTerm::Attenuation => "attenuation",
            LightTerm::Spot => "spot",
        };
        // Decimal digits by hand: `core::fmt` costs more than the rest of
        // a term's serialisation.
        let mut digits = [0u8; 20];
        let mut start = digits.len();
        let mut rest = i;
        loop {
            start -= 1;
            digits[start] = b'0' + (rest % 10) as u8;
            rest /= 10;
            if rest == 0 {
                break;
            }
        }
        let mut len = 0;
        for part in [b"lights[", &digits[start..], b"].", term.as_bytes()] {
            buf[len..len + part.len()].copy_from_slice(part);
            len += part.len();
        }
        std::str::from_utf8(&buf[..len]).expect("names are ASCII")
    }
}

impl std::fmt::Display for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name(&mut [0; 40]))
    }
}

/// Written straight into the response: naming the terms allocates nothing.
impl Serialize for Term {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.name(&mut [0; 40]))
    }
}

/// The terms the scene needs: those whose colour products are not zero on
/// some side, the attenuation of positional lights whose coefficients are
/// not (1, 0, 0), and the spot factor of cones.
pub fn modeled(lighting: &Lighting) -> Vec<Term> {
    let sides = if lighting.model.two_side {
        &[&lighting.front, &lighting.back][..]
    } else {
        &[&lighting.front][..]
    };
    let nonzero = |f: &dyn Fn(&crate::lighting::Material) -> DVec4| {
        sides.iter().any(|m| f(m).truncate() != DVec3::ZERO)
    };
    let mut out = Vec::new();
    if nonzero(&|m| m.emission) {
        out.push(Term::Emission);
    }
    if nonzero(&|m| m.ambient * lighting.model.ambient) {
        out.push(Term::GlobalAmbient);
    }
    for (i, light) in lighting.lights.iter().enumerate() {
        let terms = [
            (LightTerm::Ambient, nonzero(&|m| m.ambient * light.ambient)),
            (LightTerm::Diffuse, nonzero(&|m| m.diffuse * light.diffuse)),
            (
                LightTerm::Specular,
                nonzero(&|m| m.specular * light.specular),
            ),
            (
                LightTerm::Attenuation,
                matches!(light.position, LightPosition::Positional(_))
                    && light.attenuation != [1.0, 0.0, 0.0],
            ),
            (LightTerm::Spot, light.spot.is_cone()),
        ];
        out.extend(
            terms
                .into_iter()
                .filter(|(_, on)| *on)
                .map(|(term, _)| Term::Light(i, term)),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{LightTerm, Term};

    #[test]
    fn terms_are_named_as_the_contract_names_them() {
        let cases = [
            (Term::Emission, "emission"),
            (Term::GlobalAmbient, "global_ambient"),
            (Term::Light(0, LightTerm::Ambient), "lights[0].ambient"),
            (Term::Light(9, LightTerm::Spot), "lights[9].spot"),
            (Term::Light(10, LightTerm::Diffuse), "lights[10].diffuse"),
            (
                Term::Light(63, LightTerm::Attenuation),
                "lights[63].attenuation",
            ),
            (
                Term::Light(usize::MAX, LightTerm::Specular),
                "lights[18446744073709551615].specular",
            ),
        ];
        for (term, name) in cases {
            assert_eq!(term.to_string(), name);
            assert_eq!(serde_json::to_value(term).unwrap(), name);
        }
    }
}
