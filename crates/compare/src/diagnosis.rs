//! Naming the mistake: each deviation of the catalogue ranked by how much
//! of the error it explains, that is by the error left when glint evaluates
//! the scene with it; pairs of deviations where none explains the
//! candidate alone.
//!
//! This is model selection by residual (as Ngan, Durand and Matusik tell
//! BRDF models apart by their fit error, "Experimental Analysis of BRDF
//! Models", EGSR 2005), over models that differ from GL in one or two
//! switches.
//!
//! Which pairs: if a candidate has two mistakes, each of them alone removes
//! the part of the error it causes, so both are often among the singles
//! that reduce the error most: the pairs among the best [`PAIR_SOURCES`]
//! singles that leave less mean error than GL are tried. Where the two
//! mistakes pull the colours opposite ways, one alone may leave more error
//! than GL; so the best single is also paired with every other single, as
//! forward selection would take it. Two singles are "best": the one that
//! leaves the least largest error, and the one that leaves the least mean
//! error (removes the most of the error). Either alone misses pairs the
//! other finds: the largest error is a single channel's, which a deviation
//! touching a few vertices may lower by chance (the ambient's spot factor,
//! against a port with Phong's specular and no attenuation, where the
//! attenuation removes half of the mean error but not the largest); and a
//! deviation that shifts the mean by chance (the viewer swapped, against a
//! port without attenuation nor emission) may leave the least mean error
//! where the attenuation alone leaves a third of the largest.

use glint_lighting::deviation::{Deviation, Deviations};

/// How many of the best single deviations the pairs are drawn from: at
/// most 15 pairs.
pub const PAIR_SOURCES: usize = 6;

/// What the candidate's colours say about its mistakes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Diagnosis {
    /// Ranked, best explanation first: those that explain the candidate,
    /// then by the largest error left, the mean error left, the fewer
    /// deviations.
    pub explanations: Vec<Explanation>,
    /// The deviations this scene cannot show: their colours are GL's, to
    /// within the tier's bound, everywhere the candidate is compared (a
    /// scene without spotlights cannot tell a spot mistake). A port may
    /// have them and still match.
    pub unobservable: Vec<Deviation>,
    /// How many pairs were evaluated (0 where a single deviation explains
    /// the candidate, or GL does).
    pub pairs_tried: usize,
}

/// One model: GL with some deviations, and how well it fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Explanation {
    pub deviations: Deviations,
    /// The largest and the mean `|candidate − model|` over the compared
    /// channels: the error left.
    pub max_abs: f64,
    pub mean_abs: f64,
    /// The largest error left is within the tolerance, where GL's is not.
    pub explains: bool,
    /// The largest `|model − GL|`: how much the deviation changes this
    /// scene's colours.
    pub shift_max_abs: f64,
}

impl Explanation {
    /// The deviations' one-line details, joined by "; ".
    pub fn detail(&self) -> String {
        self.deviations
            .iter()
            .map(Deviation::detail)
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// The sums of one model over a comparison.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ModelSums {
    /// Of `|candidate − model|`.
    pub max: f64,
    pub sum: f64,
    /// Of `|model − GL|`.
    pub shift: f64,
}

impl ModelSums {
    pub fn merge(self, other: Self) -> Self {
        Self {
            max: self.max.max(other.max),
            sum: self.sum + other.sum,
            shift: self.shift.max(other.shift),
        }
    }
}

/// The thresholds of a diagnosis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Thresholds {
    /// The tier's bound: a model that moves no colour further than this is
    /// GL, for this scene.
    pub bound: f64,
    /// What "explains" means.
    pub tolerance: f64,
}

/// The diagnosis from a pass over GL and the single deviations, and a way
/// to evaluate pairs: `evaluate(models)` returns the sums of each model
/// (the first of `models` is GL), and `channels` is how many channels the
/// sums are over.
pub(crate) fn diagnose(
    singles: &[Deviations],
    sums: &[ModelSums],
    structurally_unobservable: Vec<Deviation>,
    channels: usize,
    thresholds: Thresholds,
    evaluate: impl FnOnce(&[Deviations]) -> Vec<ModelSums>,
) -> Diagnosis {
    let gl = sums[0];
    let mean = |s: &ModelSums| {
        if channels == 0 {
            0.0
        } else {
            s.sum / channels as f64
        }
    };
    let gl_explained = gl.max <= thresholds.tolerance;
    let explanation = |deviations: Deviations, s: &ModelSums| Explanation {
        deviations,
        max_abs: s.max,
        mean_abs: mean(s),
        explains: !gl_explained && s.max <= thresholds.tolerance,
        shift_max_abs: s.shift,
    };
    let mut unobservable = structurally_unobservable;
    let mut explanations = Vec::new();
    for (&d, s) in singles.iter().zip(&sums[1..]) {
        if s.shift <= thresholds.bound {
            unobservable.extend(d.iter());
        } else {
            explanations.push(explanation(d, s));
        }
    }
    let mut pairs_tried = 0;
    if !gl_explained && !explanations.iter().any(|e| e.explains) {
        let pairs = pairs(&explanations, mean(&gl));
        if !pairs.is_empty() {
            let models: Vec<Deviations> = std::iter::once(Deviations::NONE)
                .chain(pairs.iter().copied())
                .collect();
            let pair_sums = evaluate(&models);
            pairs_tried = pairs.len();
            for (&d, s) in pairs.iter().zip(&pair_sums[1..]) {
                if s.shift > thresholds.bound {
                    explanations.push(explanation(d, s));
                }
            }
        }
    }
    explanations.sort_by(|a, b| {
        b.explains
            .cmp(&a.explains)
            .then(a.max_abs.total_cmp(&b.max_abs))
            .then(a.mean_abs.total_cmp(&b.mean_abs))
            .then(a.deviations.len().cmp(&b.deviations.len()))
            .then(a.deviations.cmp(&b.deviations))
    });
    unobservable.sort();
    Diagnosis {
        explanations,
        unobservable,
        pairs_tried,
    }
}

/// The pairs among the best [`PAIR_SOURCES`] single deviations that leave
/// less mean error than GL, and the singles that leave the least largest
/// and the least mean error, each with every other one.
fn pairs(singles: &[Explanation], gl_mean: f64) -> Vec<Deviations> {
    let mut helpful: Vec<&Explanation> = singles
        .iter()
        .filter(|e| e.deviations.len() == 1 && e.mean_abs < gl_mean)
        .collect();
    helpful.sort_by(|a, b| a.mean_abs.total_cmp(&b.mean_abs));
    helpful.truncate(PAIR_SOURCES);
    let mut pairs = Vec::new();
    for (i, a) in helpful.iter().enumerate() {
        for b in &helpful[i + 1..] {
            pairs.push(a.deviations.union(b.deviations));
        }
    }
    // Forward selection from the single that leaves the least largest
    // error and from the one that leaves the least mean error.
    let one = singles.iter().filter(|e| e.deviations.len() == 1);
    let by_max = |a: &&Explanation, b: &&Explanation| {
        a.max_abs
            .total_cmp(&b.max_abs)
            .then(a.mean_abs.total_cmp(&b.mean_abs))
    };
    let by_mean = |a: &&Explanation, b: &&Explanation| {
        a.mean_abs
            .total_cmp(&b.mean_abs)
            .then(a.max_abs.total_cmp(&b.max_abs))
    };
    let starts = [one.clone().min_by(by_max), one.clone().min_by(by_mean)];
    for best in starts.into_iter().flatten() {
        for other in one.clone().filter(|e| e.deviations != best.deviations) {
            let pair = best.deviations.union(other.deviations);
            if !pairs.contains(&pair) {
                pairs.push(pair);
            }
        }
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sums(max: f64, mean: f64, shift: f64) -> ModelSums {
        ModelSums {
            max,
            sum: mean * 10.0,
            shift,
        }
    }

    const THRESHOLDS: Thresholds = Thresholds {
        bound: 1e-5,
        tolerance: 1e-5,
    };

    #[test]
    fn a_fitting_single_explains_and_comes_first() {
        let singles = [
            Deviation::PhongSpecular.into(),
            Deviation::EmissionMissing.into(),
        ];
        let d = diagnose(
            &singles,
            &[
                sums(0.3, 0.1, 0.0),
                sums(0.2, 0.05, 0.3),
                sums(1e-7, 1e-8, 0.3),
            ],
            vec![],
            10,
            THRESHOLDS,
            |_| panic!("no pair is needed"),
        );
        assert_eq!(
            d.explanations[0].deviations,
            Deviation::EmissionMissing.into()
        );
        assert!(d.explanations[0].explains);
        assert!(!d.explanations[1].explains);
        assert_eq!(d.pairs_tried, 0);
    }

    #[test]
    fn nothing_explains_a_candidate_that_gl_explains() {
        let singles = [Deviation::PhongSpecular.into()];
        let d = diagnose(
            &singles,
            &[sums(1e-6, 1e-7, 0.0), sums(1e-6, 1e-7, 0.2)],
            vec![],
            10,
            THRESHOLDS,
            |_| panic!("no pair is needed"),
        );
        assert!(d.explanations.iter().all(|e| !e.explains));
    }

    #[test]
    fn deviations_that_change_nothing_are_unobservable() {
        let singles = [
            Deviation::PhongSpecular.into(),
            Deviation::SrgbEncoded.into(),
        ];
        let d = diagnose(
            &singles,
            &[
                sums(0.3, 0.1, 0.0),
                sums(0.3, 0.1, 1e-6),
                sums(1e-7, 1e-8, 0.3),
            ],
            vec![Deviation::AttenuationIgnored],
            10,
            THRESHOLDS,
            |_| panic!("no pair is needed"),
        );
        assert_eq!(
            d.unobservable,
            [Deviation::PhongSpecular, Deviation::AttenuationIgnored]
        );
        assert_eq!(d.explanations.len(), 1);
    }

    /// Pairs come from the singles that help, best first, and a pair that
    /// fits is ranked first.
    #[test]
    fn pairs_are_drawn_from_the_singles_that_help() {
        let singles = [
            Deviation::PhongSpecular.into(),
            Deviation::EmissionMissing.into(),
            Deviation::SrgbEncoded.into(),
        ];
        let d = diagnose(
            &singles,
            &[
                sums(0.3, 0.1, 0.0),
                sums(0.2, 0.05, 0.3),
                sums(0.1, 0.02, 0.3),
                sums(0.5, 0.2, 0.3),
            ],
            vec![],
            10,
            THRESHOLDS,
            |models| {
                // The two that help, and the best (least max and least mean) with
                // the other.
                let pair = Deviations::of(&[Deviation::PhongSpecular, Deviation::EmissionMissing]);
                let best_srgb =
                    Deviations::of(&[Deviation::EmissionMissing, Deviation::SrgbEncoded]);
                assert_eq!(models, [Deviations::NONE, pair, best_srgb]);
                vec![
                    sums(0.3, 0.1, 0.0),
                    sums(1e-7, 1e-8, 0.3),
                    sums(0.4, 0.1, 0.3),
                ]
            },
        );
        assert_eq!(d.pairs_tried, 2);
        assert_eq!(d.explanations[0].deviations.len(), 2);
        assert!(d.explanations[0].explains);
    }

    /// Forward selection starts also from the single that removes the most
    /// of the error (the least mean left), not only from one that lowers
    /// the largest error a little: the other half of the pair may leave
    /// more error than GL alone, and is reached only from there.
    #[test]
    fn forward_selection_starts_from_the_least_mean_error() {
        let singles = [
            Deviation::PhongSpecular.into(),
            Deviation::AttenuationIgnored.into(),
            Deviation::AmbientSpotIgnored.into(),
        ];
        let pair = Deviations::of(&[Deviation::PhongSpecular, Deviation::AttenuationIgnored]);
        let d = diagnose(
            &singles,
            &[
                sums(0.19, 0.045, 0.0),
                // Phong's alone leaves more error than GL.
                sums(0.2, 0.085, 0.26),
                // The attenuation removes the most; the ambient's spot
                // factor lowers the largest error a little.
                sums(0.24, 0.024, 0.2),
                sums(0.189, 0.043, 0.02),
            ],
            vec![],
            10,
            THRESHOLDS,
            |models| {
                assert!(models.contains(&pair), "{models:?}");
                models
                    .iter()
                    .map(|&m| match m {
                        m if m == Deviations::NONE => sums(0.19, 0.045, 0.0),
                        m if m == pair => sums(1e-7, 1e-8, 0.3),
                        _ => sums(0.2, 0.03, 0.2),
                    })
                    .collect()
            },
        );
        assert_eq!(d.explanations[0].deviations, pair);
        assert!(d.explanations[0].explains);
    }
}
