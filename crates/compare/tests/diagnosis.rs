//! The diagnosis of the benchmark's scenes (`scenes`), on candidates drawn
//! by the reference evaluator with the port's deviations: a pair of
//! mistakes that pull the colours opposite ways is named, and a mistake
//! the scene cannot show is listed as such rather than named.

mod scenes;

use glam::DVec3;
use glint_compare::{Candidate, Comparison, Deviation, Deviations, Options, compare};
use glint_lighting::Precision;
use scenes::{TestScene, every_term, one_directional};

/// Enough vertices for every kind of point of the mesh, few enough for a
/// test.
const VERTICES: usize = 4096;

fn compared(scene: &TestScene, deviations: Deviations, precision: Precision) -> Comparison {
    let colors = scene.port_colors(deviations);
    let candidate = Candidate {
        front: &colors,
        back: None,
        alpha: false,
    };
    compare(&scene.scene(precision), &candidate, &Options::default()).unwrap()
}

/// Phong's specular (less light about the highlights: its lobe is the
/// narrower at the same exponent) with the attenuation ignored (more light
/// from the two point lights): GL's colours are nearer the candidate than
/// Phong's alone are, so Phong's specular does not lower the mean error on
/// its own, and the pair is found only by forward selection from the
/// attenuation.
#[test]
fn phong_specular_with_attenuation_ignored_is_named() {
    let scene = every_term(VERTICES);
    let port = Deviations::of(&[Deviation::PhongSpecular, Deviation::AttenuationIgnored]);
    for precision in [Precision::Accurate, Precision::Reference] {
        let found = compared(&scene, port, precision);
        let explanations = &found.diagnosis.explanations;
        let single = |d: Deviation| {
            explanations
                .iter()
                .find(|e| e.deviations == d.into())
                .unwrap()
        };
        // The case this is about: Phong alone leaves more mean error than GL.
        assert!(
            single(Deviation::PhongSpecular).mean_abs > found.error.mean_abs,
            "{precision:?}: {explanations:#?}"
        );
        let first = &explanations[0];
        assert_eq!(first.deviations, port, "{precision:?}: {explanations:#?}");
        assert!(first.explains, "{precision:?}: {first:?}");
        assert!(first.max_abs <= found.bound, "{precision:?}: {first:?}");
    }
}

/// With the light along +z and every normal tilted less than 90° from it,
/// `n·VP` is positive everywhere, so that clamping it at 0 changes nothing:
/// a port without the clamp draws GL's colours. It is listed as
/// unobservable, and nothing explains the candidate, which is within the
/// bound.
#[test]
fn diffuse_unclamped_is_unobservable_where_every_normal_faces_the_light() {
    let light = DVec3::Z;
    let scene = one_directional(VERTICES, light);
    assert!(scene.normals.iter().all(|n| n.dot(light) > 0.0));
    for precision in [Precision::Accurate, Precision::Reference] {
        let found = compared(&scene, Deviation::DiffuseUnclamped.into(), precision);
        assert!(found.error.within_bound, "{precision:?}: {:?}", found.error);
        let diagnosis = &found.diagnosis;
        assert!(
            diagnosis
                .unobservable
                .contains(&Deviation::DiffuseUnclamped),
            "{precision:?}: {diagnosis:#?}"
        );
        assert!(
            diagnosis.explanations.iter().all(|e| !e.explains),
            "{precision:?}: {diagnosis:#?}"
        );
    }
}

/// The same scene with the light from the side, so that some normals face
/// away from it: the missing clamp is seen, and named.
#[test]
fn diffuse_unclamped_is_named_where_some_normals_face_away() {
    let light = DVec3::new(1.0, 0.0, 0.3);
    let scene = one_directional(VERTICES, light);
    assert!(scene.normals.iter().any(|n| n.dot(light) < 0.0));
    for precision in [Precision::Accurate, Precision::Reference] {
        let found = compared(&scene, Deviation::DiffuseUnclamped.into(), precision);
        assert!(
            !found.error.within_bound,
            "{precision:?}: {:?}",
            found.error
        );
        let first = &found.diagnosis.explanations[0];
        assert_eq!(
            first.deviations,
            Deviation::DiffuseUnclamped.into(),
            "{precision:?}: {:#?}",
            found.diagnosis
        );
        assert!(first.explains, "{precision:?}: {first:?}");
    }
}
