//! What the responses of `/v1/shade` and `/v1/render` share: the precision
//! and its bound, warnings, the term breakdown and its statistics, and the
//! names of the terms an evaluation modelled.

use glam::{DVec3, DVec4};
use glint_lighting::terms::{Breakdown, ColorStat, FactorStat, LightTerms, Summary};
use glint_lighting::{LightPosition, LightSet, Material, Precision, SurfaceMaterial};
use serde::Serialize;

use crate::scene::{Warning, wire};

#[derive(Debug, Serialize)]
pub struct PrecisionOut {
    pub mode: wire::Precision,
    pub max_abs_error: f64,
}

impl From<Precision> for PrecisionOut {
    fn from(mode: Precision) -> Self {
        Self {
            mode: mode.into(),
            max_abs_error: mode.max_abs_error(),
        }
    }
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

/// The largest shininess for which the f32 tiers keep their documented
/// bounds when normals are used as given. With unit normals the specular
/// base is a cosine, evaluated without losing the digits near 1, and the
/// bounds hold at any shininess; a raw normal's `n·ĥ` is a plain f32 whose
/// relative error, about 1e-7, the power multiplies by the shininess.
pub const MAX_BOUNDED_RAW_SHININESS: f64 = 64.0;

/// Why an f32 tier cannot promise its bound for `material` under `lights`, a sentence
/// per reason; none when it can. Its errors are relative to the size of the
/// terms, and the bound absolute. Without negative colours no term is below
/// zero, so a term larger than 1 saturates the clamped colour and its
/// rounding never shows; negative colours let large terms cancel to a small
/// colour that keeps their error.
fn precision_bound_reasons(lights: &LightSet, material: &SurfaceMaterial) -> Vec<String> {
    let mut reasons = Vec::new();
    let colours = [lights.model.ambient]
        .into_iter()
        .chain(
            [&material.front, &material.back]
                .into_iter()
                .flat_map(|m| [m.ambient, m.diffuse, m.specular, m.emission]),
        )
        .chain(
            lights
                .lights()
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
    let shininess = material.front.shininess.max(material.back.shininess);
    if !lights.model.normalize_normals && shininess > MAX_BOUNDED_RAW_SHININESS {
        reasons.push(format!(
            "a shininess of {shininess} with normalize_normals off: above \
             {MAX_BOUNDED_RAW_SHININESS}, f32 cannot hold the documented bound of this \
             precision near highlights; `reference` is exact"
        ));
    }
    reasons
}

/// [`precision_bound_reasons`] as warnings, when `precision` is an f32
/// tier: `uses` are the materials lit and how many things (vertices,
/// objects) each lights; each reason is one warning, counting the things of
/// every material it holds for.
pub fn precision_warnings<'m>(
    precision: Precision,
    lights: &LightSet,
    uses: impl IntoIterator<Item = (&'m SurfaceMaterial, usize)>,
) -> Vec<Warning> {
    if precision.tier().is_none() {
        return Vec::new();
    }
    let mut warnings: Vec<Warning> = Vec::new();
    for (material, count) in uses.into_iter().filter(|(_, count)| *count > 0) {
        for reason in precision_bound_reasons(lights, material) {
            match warnings.iter_mut().find(|w| w.detail == reason) {
                Some(warning) => warning.count += count,
                None => warnings.push(Warning {
                    code: "precision_bound",
                    count,
                    detail: reason,
                }),
            }
        }
    }
    warnings
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
    pub(crate) fn name<'b>(&self, buf: &'b mut [u8; 40]) -> &'b str {
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
        let mut digits = [0u8; 20];
        let mut len = 0;
        for part in [
            b"lights[",
            decimal(i as u64, &mut digits),
            b"].",
            term.as_bytes(),
        ] {
            buf[len..len + part.len()].copy_from_slice(part);
            len += part.len();
        }
        std::str::from_utf8(&buf[..len]).expect("names are ASCII")
    }
}

/// The decimal digits of `n`, written at the end of `digits` by hand:
/// `core::fmt` costs more than the rest of a term's serialisation, or of a
/// log line.
pub(crate) fn decimal(n: u64, digits: &mut [u8; 20]) -> &[u8] {
    let mut start = digits.len();
    let mut rest = n;
    loop {
        start -= 1;
        digits[start] = b'0' + (rest % 10) as u8;
        rest /= 10;
        if rest == 0 {
            break;
        }
    }
    &digits[start..]
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

/// The terms that `material` under `lights` needs: those whose colour
/// products are not zero on some side, the attenuation of positional lights
/// whose coefficients are not (1, 0, 0), and the spot factor of cones.
pub fn modeled(lights: &LightSet, material: &SurfaceMaterial) -> Vec<Term> {
    let sides = if lights.model.two_side {
        &[&material.front, &material.back][..]
    } else {
        &[&material.front][..]
    };
    let nonzero =
        |f: &dyn Fn(&Material) -> DVec4| sides.iter().any(|m| f(m).truncate() != DVec3::ZERO);
    // At most two terms and five for each light: one allocation.
    let mut out = Vec::with_capacity(2 + 5 * lights.lights().len());
    if nonzero(&|m| m.emission) {
        out.push(Term::Emission);
    }
    if nonzero(&|m| m.ambient * lights.model.ambient) {
        out.push(Term::GlobalAmbient);
    }
    for (i, light) in lights.lights().iter().enumerate() {
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
