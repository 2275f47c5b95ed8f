//! The mistakes that hand-written ports of GL's fixed-function lighting make,
//! each a switch of glint's own model, so that the reference evaluator
//! ([`crate::reference::evaluate_port`]) can compute what a port with that
//! mistake would have drawn. Comparing a port's colours with these is how
//! `/v1/compare` names the mistake.
//!
//! The first sixteen names are fixed by the API's contract. The rest come
//! from the commits and reviews of real ports: the spot factor left off the
//! per-light ambient term (Mesa, 1997: "spotlight factor now effects ambient
//! lighting"), the cone of a directional light ignored (ANGLE's GLES1
//! shader), both exponents clamped to 128 (gl4es, Mesa), `pow(0, 0)` taken
//! as 0 (gl4es), and the lit alpha summed over the terms (ANGLE's GLES1
//! shader) where GL takes the diffuse material's.
//!
//! A deviation that the scene gives no chance to show (attenuation on a
//! scene of directional lights) leaves the colours as GL's: the switch is
//! still defined, it just changes nothing.

use std::fmt;

/// One way a port departs from section 2.14.1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Deviation {
    /// Specular from Phong's `(r⊙VP_e)^s` where GL uses `(n⊙ĥ)^s`.
    PhongSpecular,
    /// The local viewer where GL has the infinite one, or the reverse.
    ViewerSwapped,
    /// `n·(VP_pli + VP_e)` as the specular base, without normalising `ĥ`.
    HalfVectorUnnormalized,
    /// Specular where `n·VP_pli ≤ 0` too (`f_i` = 1 everywhere).
    SpecularUngated,
    /// `att_i` = 1 for lights at a point.
    AttenuationIgnored,
    /// The spot exponent taken as 0: full light inside the cone.
    SpotExponentIgnored,
    /// `cos(c_rli)` taken of the cutoff's degrees as if they were radians.
    SpotCutoffRadians,
    /// No `a_cm·a_cs` term.
    GlobalAmbientMissing,
    /// No `a_cm·a_cli` terms.
    LightAmbientMissing,
    /// No `e_cm` term.
    EmissionMissing,
    /// Normals used as given although `normalize_normals` is on.
    NormalsUnnormalized,
    /// `n·VP_pli` not clamped at 0 in the diffuse term.
    DiffuseUnclamped,
    /// Back faces lit as front faces: the back colour is the front colour.
    TwoSideIgnored,
    /// The specular sum added before the clamp, as with a single colour.
    SeparateSpecularIgnored,
    /// The colour written sRGB-encoded where GL writes it linear.
    SrgbEncoded,
    /// No clamp to [0, 1] of the colour.
    UnclampedOutput,
    /// The per-light ambient term not multiplied by the spot factor.
    AmbientSpotIgnored,
    /// No spot cone for lights at infinity (`spot_i` = 1 where `w = 0`).
    DirectionalSpotIgnored,
    /// The shininess and the spot exponent clamped to 128.
    ExponentsClamped,
    /// `0^0` taken as 0 in the specular and spot powers (GL: 1).
    ZeroPowerZero,
    /// The lit alpha summed over the terms' alphas, where GL takes the
    /// diffuse material's alpha.
    AlphaSummed,
}

/// The largest exponent a port with [`Deviation::ExponentsClamped`] uses:
/// GL's own limit on `GL_SHININESS` and `GL_SPOT_EXPONENT`.
pub const CLAMPED_EXPONENT: f64 = 128.0;

impl Deviation {
    /// The catalogue, in the order of the contract, then the additions.
    pub const ALL: [Deviation; 21] = [
        Deviation::PhongSpecular,
        Deviation::ViewerSwapped,
        Deviation::HalfVectorUnnormalized,
        Deviation::SpecularUngated,
        Deviation::AttenuationIgnored,
        Deviation::SpotExponentIgnored,
        Deviation::SpotCutoffRadians,
        Deviation::GlobalAmbientMissing,
        Deviation::LightAmbientMissing,
        Deviation::EmissionMissing,
        Deviation::NormalsUnnormalized,
        Deviation::DiffuseUnclamped,
        Deviation::TwoSideIgnored,
        Deviation::SeparateSpecularIgnored,
        Deviation::SrgbEncoded,
        Deviation::UnclampedOutput,
        Deviation::AmbientSpotIgnored,
        Deviation::DirectionalSpotIgnored,
        Deviation::ExponentsClamped,
        Deviation::ZeroPowerZero,
        Deviation::AlphaSummed,
    ];

    /// The name of the API (`phong_specular`).
    pub fn name(self) -> &'static str {
        match self {
            Deviation::PhongSpecular => "phong_specular",
            Deviation::ViewerSwapped => "viewer_swapped",
            Deviation::HalfVectorUnnormalized => "half_vector_unnormalized",
            Deviation::SpecularUngated => "specular_ungated",
            Deviation::AttenuationIgnored => "attenuation_ignored",
            Deviation::SpotExponentIgnored => "spot_exponent_ignored",
            Deviation::SpotCutoffRadians => "spot_cutoff_radians",
            Deviation::GlobalAmbientMissing => "global_ambient_missing",
            Deviation::LightAmbientMissing => "light_ambient_missing",
            Deviation::EmissionMissing => "emission_missing",
            Deviation::NormalsUnnormalized => "normals_unnormalized",
            Deviation::DiffuseUnclamped => "diffuse_unclamped",
            Deviation::TwoSideIgnored => "two_side_ignored",
            Deviation::SeparateSpecularIgnored => "separate_specular_ignored",
            Deviation::SrgbEncoded => "srgb_encoded",
            Deviation::UnclampedOutput => "unclamped_output",
            Deviation::AmbientSpotIgnored => "ambient_spot_ignored",
            Deviation::DirectionalSpotIgnored => "directional_spot_ignored",
            Deviation::ExponentsClamped => "exponents_clamped",
            Deviation::ZeroPowerZero => "zero_power_zero",
            Deviation::AlphaSummed => "alpha_summed",
        }
    }

    /// What the port computes, against what GL computes, in one line.
    pub fn detail(self) -> &'static str {
        match self {
            Deviation::PhongSpecular => "specular from (r·v)^s, not (n·h)^s",
            Deviation::ViewerSwapped => {
                "the local viewer where GL has the infinite one, or the reverse"
            }
            Deviation::HalfVectorUnnormalized => {
                "specular from (n·(VP + VP_e))^s: the half vector not normalised"
            }
            Deviation::SpecularUngated => "specular also where n·VP ≤ 0 (f_i ignored)",
            Deviation::AttenuationIgnored => "no attenuation: att = 1 for lights at a point",
            Deviation::SpotExponentIgnored => "spot exponent ignored: full light inside the cone",
            Deviation::SpotCutoffRadians => "spot cutoff's cosine taken of its degrees as radians",
            Deviation::GlobalAmbientMissing => "no global ambient term (a_cm·a_cs)",
            Deviation::LightAmbientMissing => "no per-light ambient terms (a_cm·a_cli)",
            Deviation::EmissionMissing => "no emission term (e_cm)",
            Deviation::NormalsUnnormalized => "normals used as given, not normalised",
            Deviation::DiffuseUnclamped => "diffuse from n·VP, not max(n·VP, 0)",
            Deviation::TwoSideIgnored => "back faces lit as front faces (two-sided lighting off)",
            Deviation::SeparateSpecularIgnored => {
                "specular added before the clamp (separate specular colour ignored)"
            }
            Deviation::SrgbEncoded => "colours sRGB-encoded where GL writes them linear",
            Deviation::UnclampedOutput => "colours not clamped to [0, 1]",
            Deviation::AmbientSpotIgnored => "per-light ambient not multiplied by the spot factor",
            Deviation::DirectionalSpotIgnored => "no spot cone for directional lights (w = 0)",
            Deviation::ExponentsClamped => "shininess and spot exponent clamped to 128",
            Deviation::ZeroPowerZero => "0^0 taken as 0 in the specular and spot powers, not 1",
            Deviation::AlphaSummed => {
                "alpha summed over the lit terms, not the diffuse material's alpha"
            }
        }
    }

    /// The deviation of an API name.
    pub fn from_name(name: &str) -> Option<Deviation> {
        Deviation::ALL.into_iter().find(|d| d.name() == name)
    }

    /// Whether the deviation acts on the output colour alone, once the
    /// terms are summed: these need no term of the equation evaluated again.
    pub fn is_output(self) -> bool {
        matches!(
            self,
            Deviation::SeparateSpecularIgnored
                | Deviation::SrgbEncoded
                | Deviation::UnclampedOutput
        )
    }

    fn bit(self) -> u32 {
        1 << self as u32
    }
}

impl fmt::Display for Deviation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A set of deviations: what one port gets wrong. The empty set is GL.
#[derive(Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Deviations(u32);

// One bit per deviation.
const _: () = assert!(Deviation::ALL.len() <= u32::BITS as usize);

impl Deviations {
    /// GL itself.
    pub const NONE: Deviations = Deviations(0);

    /// The set of `deviations`.
    pub fn of(deviations: &[Deviation]) -> Self {
        deviations.iter().fold(Self::NONE, |set, &d| set.with(d))
    }

    /// This set and `d`.
    #[must_use]
    pub fn with(self, d: Deviation) -> Self {
        Self(self.0 | d.bit())
    }

    /// Both sets.
    #[must_use]
    pub fn union(self, other: Deviations) -> Self {
        Self(self.0 | other.0)
    }

    pub fn contains(self, d: Deviation) -> bool {
        self.0 & d.bit() != 0
    }

    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// The deviations of the set, in the catalogue's order.
    pub fn iter(self) -> impl Iterator<Item = Deviation> {
        Deviation::ALL
            .into_iter()
            .filter(move |d| self.contains(*d))
    }
}

impl From<Deviation> for Deviations {
    fn from(d: Deviation) -> Self {
        Self::NONE.with(d)
    }
}

impl fmt::Debug for Deviations {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_set().entries(self.iter()).finish()
    }
}

impl fmt::Display for Deviations {
    /// The names joined by `+`; `gl` for the empty set.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_empty() {
            return f.write_str("gl");
        }
        for (i, d) in self.iter().enumerate() {
            if i > 0 {
                f.write_str("+")?;
            }
            f.write_str(d.name())?;
        }
        Ok(())
    }
}

/// The sRGB transfer curve (IEC 61966-2-1) of a linear value: what a port
/// with [`Deviation::SrgbEncoded`] writes. Values below 0 stay on the
/// linear segment; above 1 the curve continues.
pub fn srgb_encode(c: f64) -> f64 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_round_trip() {
        for d in Deviation::ALL {
            assert_eq!(Deviation::from_name(d.name()), Some(d));
            assert_eq!(
                Deviation::ALL
                    .iter()
                    .filter(|e| e.name() == d.name())
                    .count(),
                1
            );
            assert!(!d.detail().is_empty());
        }
        assert_eq!(Deviation::from_name("phong"), None);
    }

    #[test]
    fn sets_hold_what_was_put_in() {
        let set = Deviations::of(&[Deviation::SrgbEncoded, Deviation::PhongSpecular]);
        assert!(set.contains(Deviation::PhongSpecular));
        assert!(!set.contains(Deviation::ViewerSwapped));
        assert_eq!(set.len(), 2);
        assert_eq!(set.to_string(), "phong_specular+srgb_encoded");
        assert_eq!(Deviations::NONE.to_string(), "gl");
    }

    /// The curve's own anchor points: 0, the joint of its two pieces and 1.
    #[test]
    fn srgb_encoding_meets_its_definition() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-15);
        // At the joint both pieces give 0.0404482…
        let joint = 0.003_130_8;
        assert!((12.92 * joint - (1.055 * f64::powf(joint, 1.0 / 2.4) - 0.055)).abs() < 1e-7);
        // 0.5 encodes to 0.735357 (IEC 61966-2-1's curve, computed by hand).
        assert!((srgb_encode(0.5) - 0.735_356_983).abs() < 1e-8);
    }
}
