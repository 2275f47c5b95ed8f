//! The edge cases the module docs of `glint_lighting` decide, each with the
//! value the decision implies, computed by hand.

use glam::{DVec3, DVec4};
use glint_lighting::{
    ColorControl, Light, LightModel, LightPosition, MAX_ATTENUATION, MAX_RAW_NORMAL, Material,
    Side, SpecularModel, Spot, SurfaceMaterial, Viewer, spec_pow, unit_or_zero,
};

use super::support::{
    BLACK, R2, Scene, assert_finite_breakdown, assert_unit_color, black_light, black_material,
    dark_model, eye_space, front, front_terms, grey, light_set, rgb, unit,
};

const ORIGIN: DVec3 = DVec3::ZERO;
const UP: DVec3 = DVec3::Z;

// ---------------------------------------------------------------------------
// 0^0 = 1
// ---------------------------------------------------------------------------

#[test]
fn spec_pow_follows_section_2_1_1() {
    assert_eq!(spec_pow(0.0, 0.0), 1.0); // 0^0 = 1
    assert_eq!(spec_pow(-0.5, 0.0), 1.0); // clamped to 0, then 0^0
    assert_eq!(spec_pow(0.0, 2.0), 0.0);
    assert_eq!(spec_pow(-0.5, 2.0), 0.0); // clamped at 0 first, not (-0.5)² = 0.25
    assert_close!(spec_pow(0.5, 3.0), 0.125);
    assert_eq!(spec_pow(2.0, 1000.0), glint_lighting::MAX_POWER); // 2^1000, capped
}

/// Shininess 0 where n·ĥ = 0 but n·VP > 0. Light at VP = (1,0,1)/√2, viewer
/// at infinity along (1,0,-1)/√2 (below the tangent plane):
/// VP + VP_e = (√2, 0, 0), so ĥ = +x and n·ĥ = 0 exactly; n·VP = 1/√2 > 0 so
/// f_i = 1 and the specular term is 0^0·s_cm·s_cli = s_cm·s_cli. With any
/// positive shininess it is 0.
#[test]
fn shininess_zero_with_the_halfway_vector_in_the_tangent_plane_gives_full_specular() {
    let light = Light {
        specular: rgb(1.0, 0.5, 0.25),
        ..black_light(LightPosition::Directional(DVec3::new(R2, 0.0, R2)))
    };
    for (shininess, factor) in [(0.0, 1.0), (1.0, 0.0), (1e-3, 0.0)] {
        let mut scene = eye_space(
            dark_model(),
            Material {
                specular: grey(0.8),
                shininess,
                ..black_material()
            },
            vec![light],
        );
        scene.lights.viewer = Viewer::Infinite(DVec3::new(R2, 0.0, -R2));
        assert_close!(
            front_terms(&scene, ORIGIN, UP).lights[0].specular,
            DVec3::new(0.8, 0.4, 0.2) * factor,
            tol = 1e-12,
            "shininess {shininess}"
        );
    }
}

// ---------------------------------------------------------------------------
// Zero vectors
// ---------------------------------------------------------------------------

#[test]
fn unit_or_zero_of_zero_is_zero() {
    assert_eq!(unit_or_zero(DVec3::ZERO), DVec3::ZERO);
    assert_eq!(unit_or_zero(DVec3::new(0.0, -0.0, 0.0)), DVec3::ZERO);
    assert_eq!(unit_or_zero(DVec3::new(f64::NAN, 0.0, 0.0)), DVec3::ZERO);
    assert_eq!(
        unit_or_zero(DVec3::new(f64::INFINITY, 0.0, 0.0)),
        DVec3::ZERO
    );
    assert_close!(
        unit_or_zero(DVec3::new(3.0, 0.0, 4.0)),
        DVec3::new(0.6, 0.0, 0.8)
    );
}

/// A zero normal: n⊙VP = 0, hence no diffuse and f_i = 0, hence no specular
/// even with shininess 0 (where (n⊙ĥ)^0 = 1). What remains:
/// e_cm + a_cm·a_cs + a_cm·a_cli = 0.1 + 0.5·0.2 + 0.5·0.4 = 0.4,
/// with normalisation on or off, for directional and positional lights.
#[test]
fn zero_normal_keeps_only_emission_and_ambient() {
    let material = Material {
        emission: grey(0.1),
        ambient: grey(0.5),
        diffuse: grey(1.0),
        specular: grey(1.0),
        shininess: 0.0,
    };
    for position in [
        LightPosition::Directional(DVec3::Z),
        LightPosition::Positional(DVec3::new(1.0, 2.0, 3.0)),
    ] {
        for normalize in [true, false] {
            let model = LightModel {
                ambient: grey(0.2),
                normalize_normals: normalize,
                ..LightModel::default()
            };
            let light = Light {
                position,
                ambient: grey(0.4),
                ..Light::default()
            };
            let scene = eye_space(model, material, vec![light]);
            let b = front_terms(&scene, ORIGIN, DVec3::ZERO);
            let context = format!("{position:?}, normalize {normalize}");
            assert_close!(b.lights[0].diffuse, DVec3::ZERO, tol = 0.0, "{context}");
            assert_close!(b.lights[0].specular, DVec3::ZERO, tol = 0.0, "{context}");
            assert_close!(
                front(&scene, ORIGIN, DVec3::ZERO),
                grey(0.1 + 0.5 * 0.2 + 0.5 * 0.4),
                tol = 1e-12,
                "{context}"
            );
        }
    }
}

/// A positional light exactly at the vertex: d = 0 and VP_pli is the zero
/// vector, so n⊙VP = 0 (no diffuse, f_i = 0: no specular, even with
/// shininess 0), and att = 1/k0.
/// - k = (0.5, 1, 1): att = 2, ambient term 2·a_cm·a_cli = 2·0.5·0.2 = 0.2;
/// - k = (0, 1, 1): 1/0, capped at MAX_ATTENUATION: 1e10·0.1 = 1e9, which
///   clamps to 1;
/// - the same with a_cli = 0: the light adds exactly nothing (0, not NaN).
#[test]
fn positional_light_at_the_vertex_gives_only_ambient() {
    let v = DVec3::new(1.0, 2.0, 3.0);
    let material = Material {
        ambient: grey(0.5),
        diffuse: grey(1.0),
        specular: grey(1.0),
        shininess: 0.0,
        ..black_material()
    };
    let light = |k: [f64; 3], ambient: f64| Light {
        ambient: grey(ambient),
        diffuse: grey(1.0),
        specular: grey(1.0),
        attenuation: k,
        ..black_light(LightPosition::Positional(v))
    };
    for (k, ambient, att, color) in [
        ([0.5, 1.0, 1.0], 0.2, 2.0, 2.0 * 0.5 * 0.2),
        ([0.0, 1.0, 1.0], 0.2, MAX_ATTENUATION, 1.0),
        ([0.0, 1.0, 1.0], 0.0, MAX_ATTENUATION, 0.0),
    ] {
        let scene = eye_space(dark_model(), material, vec![light(k, ambient)]);
        for n in [UP, DVec3::NEG_X, DVec3::ZERO] {
            let b = front_terms(&scene, v, n);
            let context = format!("k = {k:?}, a_cli = {ambient}, n = {n:?}");
            assert_close!(b.lights[0].attenuation, att, tol = 0.0, "{context}");
            assert_close!(b.lights[0].spot, 1.0, tol = 0.0, "{context}");
            // Relative tolerance: the term is 1e9 when att is the cap.
            assert_close!(
                b.lights[0].ambient,
                DVec3::splat(att * 0.5 * ambient),
                tol = 1e-12 * att,
                "{context}"
            );
            assert_close!(b.lights[0].diffuse, DVec3::ZERO, tol = 0.0, "{context}");
            assert_close!(b.lights[0].specular, DVec3::ZERO, tol = 0.0, "{context}");
            assert_close!(front(&scene, v, n), grey(color), tol = 1e-12, "{context}");
        }
    }
}

/// A spotlight at the vertex: P_pli V = 0, so the clamped dot product is 0.
/// A 45° cone (cos > 0) excludes it (spot 0, the light adds nothing); a 90°
/// cone with exponent 0 has it on its edge (0 ≥ cos 90° = 0, 0^0 = 1).
#[test]
fn spotlight_at_the_vertex() {
    let v = DVec3::new(1.0, 2.0, 3.0);
    let material = Material {
        ambient: grey(0.5),
        ..black_material()
    };
    for (cutoff, spot) in [(45.0, 0.0), (90.0, 1.0), (180.0, 1.0)] {
        let light = Light {
            ambient: grey(1.0),
            attenuation: [2.0, 0.0, 0.0],
            spot: Spot {
                direction: DVec3::NEG_Z,
                exponent: 0.0,
                cutoff,
            },
            ..black_light(LightPosition::Positional(v))
        };
        let scene = eye_space(dark_model(), material, vec![light]);
        let b = front_terms(&scene, v, UP);
        assert_close!(b.lights[0].spot, spot, tol = 0.0, "cutoff {cutoff}");
        // att·spot·a_cm·a_cli = (1/2)·spot·0.5.
        assert_close!(
            b.lights[0].ambient,
            DVec3::splat(0.5 * spot * 0.5),
            tol = 1e-12,
            "cutoff {cutoff}"
        );
    }
}

/// The attenuation cap also holds near the vertex: a light 1e-6 above it with
/// k = (0,0,1) has 1/d² = 1e12 > MAX_ATTENUATION = 1e10.
#[test]
fn attenuation_is_capped_near_the_vertex() {
    let light = Light {
        attenuation: [0.0, 0.0, 1.0],
        ..black_light(LightPosition::Positional(DVec3::new(0.0, 0.0, 1e-6)))
    };
    let scene = eye_space(dark_model(), black_material(), vec![light]);
    assert_eq!(
        front_terms(&scene, ORIGIN, UP).lights[0].attenuation,
        MAX_ATTENUATION
    );
    // 2 units away: 1/4, untouched.
    assert_close!(
        front_terms(&scene, DVec3::new(0.0, 0.0, -2.0 + 1e-6), UP).lights[0].attenuation,
        0.25
    );
}

// ---------------------------------------------------------------------------
// The spot cone's edges
// ---------------------------------------------------------------------------

#[test]
fn cos_cutoff_is_exact_at_0_and_90() {
    let spot = |cutoff| Spot {
        cutoff,
        ..Spot::default()
    };
    assert_eq!(spot(90.0).cos_cutoff(), 0.0);
    assert_eq!(spot(0.0).cos_cutoff(), 1.0);
    assert_close!(spot(60.0).cos_cutoff(), 0.5);
    assert!(!spot(180.0).is_cone());
    assert!(spot(90.0).is_cone());
}

/// A spotlight at the origin pointing down (ŝ = -z) with a 90° cutoff,
/// watched through its ambient term (a_cm·a_cli = 0.5, so the term is
/// 0.5·spot). P_pli V ⊙ ŝ is the clamped cosine of the angle from the axis:
/// - in front, on the axis (V = (0,0,-2)): 1 → spot 1^e = 1;
/// - in front at 45° (V = (2,0,-2)): 1/√2 → (1/√2)^e;
/// - in the light's plane (V = (2,0,0)): 0 ≥ cos 90° = 0, on the edge: lit,
///   spot = 0^e: 1 for e = 0, 0 for e > 0;
/// - behind (V = (0,0,2), raw cosine −1, clamped to 0): the same as the plane.
#[test]
fn cutoff_exactly_90() {
    let material = Material {
        ambient: grey(0.5),
        ..black_material()
    };
    let scene = |exponent| {
        let light = Light {
            ambient: grey(1.0),
            spot: Spot {
                direction: DVec3::NEG_Z,
                exponent,
                cutoff: 90.0,
            },
            ..black_light(LightPosition::Positional(ORIGIN))
        };
        eye_space(dark_model(), material, vec![light])
    };
    for (exponent, v, spot) in [
        (0.0, DVec3::new(0.0, 0.0, -2.0), 1.0),
        (0.0, DVec3::new(2.0, 0.0, -2.0), 1.0),
        (0.0, DVec3::new(2.0, 0.0, 0.0), 1.0),
        (0.0, DVec3::new(0.0, 0.0, 2.0), 1.0),
        (0.0, DVec3::new(2.0, 0.0, 2.0), 1.0),
        (2.0, DVec3::new(0.0, 0.0, -2.0), 1.0),
        (2.0, DVec3::new(2.0, 0.0, -2.0), 0.5),
        (2.0, DVec3::new(2.0, 0.0, 0.0), 0.0),
        (2.0, DVec3::new(0.0, 0.0, 2.0), 0.0),
        (2.0, DVec3::new(2.0, 0.0, 2.0), 0.0),
    ] {
        let scene = scene(exponent);
        let b = front_terms(&scene, v, UP);
        let context = format!("exponent {exponent}, vertex {v:?}");
        assert_close!(b.lights[0].spot, spot, tol = 1e-12, "{context}");
        assert_close!(
            front(&scene, v, UP),
            grey(0.5 * spot),
            tol = 1e-12,
            "{context}"
        );
    }
}

/// A 0° cutoff (cos = 1): only points exactly on the axis are lit.
#[test]
fn cutoff_exactly_0() {
    let light = Light {
        ambient: grey(1.0),
        spot: Spot {
            direction: DVec3::NEG_Z,
            exponent: 5.0,
            cutoff: 0.0,
        },
        ..black_light(LightPosition::Positional(ORIGIN))
    };
    let material = Material {
        ambient: grey(0.5),
        ..black_material()
    };
    let scene = eye_space(dark_model(), material, vec![light]);
    for (v, spot) in [
        (DVec3::new(0.0, 0.0, -3.0), 1.0), // on the axis: 1 ≥ 1, 1^5 = 1
        (DVec3::new(0.0, 0.0, -1e6), 1.0),
        (DVec3::new(1e-6, 0.0, -3.0), 0.0), // a hair off the axis
        (DVec3::new(0.0, 0.0, 3.0), 0.0),   // behind: 0 < 1
        (DVec3::new(3.0, 0.0, 0.0), 0.0),
    ] {
        let b = front_terms(&scene, v, UP);
        assert_close!(b.lights[0].spot, spot, tol = 0.0, "vertex {v:?}");
        assert_close!(
            b.lights[0].ambient,
            DVec3::splat(0.5 * spot),
            tol = 0.0,
            "vertex {v:?}"
        );
    }
}

/// The cone test is `≥ cos(cutoff)`: a direction whose cosine with ŝ equals
/// `cos_cutoff()` exactly is lit. With ŝ = -z and P_pli V = (√(1−c²), 0, −c),
/// the dot product is exactly c; just outside (c − 1e-9) the spot is 0.
/// Through a directional light (P_pli V = −VP_pli) the same holds in the
/// reference evaluator.
#[test]
fn vertex_exactly_on_the_cone_edge_is_lit() {
    for cutoff in [30.0, 45.0, 60.0, 89.0, 1.0] {
        let spot = Spot {
            direction: DVec3::NEG_Z,
            exponent: 2.0,
            cutoff,
        };
        let c = spot.cos_cutoff();
        let on_edge = DVec3::new((1.0 - c * c).sqrt(), 0.0, -c);
        assert_eq!(on_edge.dot(spot.direction), c);
        assert_close!(spot.factor(on_edge), c * c, tol = 1e-12, "cutoff {cutoff}");
        let outside = DVec3::new((1.0 - (c - 1e-9).powi(2)).sqrt(), 0.0, -(c - 1e-9));
        assert_eq!(spot.factor(outside), 0.0, "cutoff {cutoff}");

        let light = Light {
            ambient: grey(1.0),
            spot,
            ..black_light(LightPosition::Directional(-on_edge))
        };
        let scene = eye_space(
            dark_model(),
            Material {
                ambient: grey(1.0),
                ..black_material()
            },
            vec![light],
        );
        assert_close!(
            front_terms(&scene, ORIGIN, UP).lights[0].spot,
            c * c,
            tol = 1e-12,
            "cutoff {cutoff}"
        );
    }
}

// ---------------------------------------------------------------------------
// Grazing light
// ---------------------------------------------------------------------------

/// A light in the tangent plane (VP = +x, n·VP = 0 exactly): no diffuse and
/// f_i = 0, so no specular even with shininess 0.
///
/// Just above it, VP = (c, 0, s) with s = sin θ small: diffuse s·d_cm·d_cli;
/// ĥ = (c, 0, 1+s)/√(c² + (1+s)²) = (c, 0, 1+s)/√(2+2s), so
/// (n·ĥ)² = (1+s)²/(2+2s) = (1+s)/2: specular (1+s)/2·s_cm·s_cli with
/// shininess 2, and the full s_cm·s_cli with shininess 0 (a jump from 0).
#[test]
fn grazing_light() {
    let material = |shininess| Material {
        diffuse: grey(0.8),
        specular: grey(0.5),
        shininess,
        ..black_material()
    };
    let light = |towards_light| Light {
        diffuse: grey(1.0),
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(towards_light))
    };
    for shininess in [0.0, 2.0] {
        let scene = eye_space(dark_model(), material(shininess), vec![light(DVec3::X)]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(
            b.lights[0].diffuse,
            DVec3::ZERO,
            tol = 0.0,
            "shininess {shininess}"
        );
        assert_close!(
            b.lights[0].specular,
            DVec3::ZERO,
            tol = 0.0,
            "shininess {shininess}"
        );
    }

    let just_above = unit(1.0, 0.0, 1e-3);
    let s = just_above.z; // n·VP
    for (shininess, factor) in [(0.0, 1.0), (2.0, (1.0 + s) / 2.0)] {
        let scene = eye_space(dark_model(), material(shininess), vec![light(just_above)]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(
            b.lights[0].diffuse,
            DVec3::splat(0.8 * s),
            tol = 1e-15,
            "shininess {shininess}"
        );
        assert_close!(
            b.lights[0].specular,
            DVec3::splat(0.5 * factor),
            tol = 1e-12,
            "shininess {shininess}"
        );
    }
}

// ---------------------------------------------------------------------------
// Negative light colours
// ---------------------------------------------------------------------------

/// A light with d_cli = (-1, -0.5, 0) overhead on GL's default material
/// (d_cm = 0.8) subtracts: diffuse term (-0.8, -0.4, 0); with the global
/// ambient 0.2·0.2 = 0.04 the sum is (-0.76, -0.36, 0.04) → (0, 0, 0.04).
/// A white light added to it is reduced before clamping, not after:
/// 0.04 + (-0.8, -0.4, 0) + 0.8 = (0.04, 0.44, 0.84).
#[test]
fn negative_light_colours_subtract_before_clamping() {
    let negative = Light {
        diffuse: rgb(-1.0, -0.5, 0.0),
        specular: BLACK,
        ..Light::default()
    };
    let white = Light {
        specular: BLACK,
        ..Light::default()
    };
    let scene = eye_space(LightModel::default(), Material::default(), vec![negative]);
    let b = front_terms(&scene, ORIGIN, UP);
    assert_close!(b.lights[0].diffuse, DVec3::new(-0.8, -0.4, 0.0));
    assert_close!(b.unclamped(), DVec3::new(0.04 - 0.8, 0.04 - 0.4, 0.04));
    assert_close!(front(&scene, ORIGIN, UP), rgb(0.0, 0.0, 0.04));

    let both = eye_space(
        LightModel::default(),
        Material::default(),
        vec![negative, white],
    );
    assert_close!(front(&both, ORIGIN, UP), rgb(0.04, 0.44, 0.84));
}

/// Negative ambient and specular light colours are signed terms too: a_cli =
/// -0.5 on a_cm = 0.2 gives -0.1; s_cli = -1 on s_cm = 0.5 overhead
/// (n·ĥ = 1) gives -0.5. With separate specular, the negative secondary
/// clamps to 0 on its own and does not darken the primary.
#[test]
fn negative_ambient_and_specular_light_colours() {
    let material = Material {
        ambient: grey(0.2),
        diffuse: grey(0.8),
        specular: grey(0.5),
        shininess: 4.0,
        ..black_material()
    };
    let light = Light {
        ambient: grey(-0.5),
        diffuse: grey(1.0),
        specular: grey(-1.0),
        ..Light::default()
    };
    for (control, expected) in [
        // 0.8 − 0.1 − 0.5
        (ColorControl::Single, 0.8 - 0.1 - 0.5),
        // clamp(0.8 − 0.1) + clamp(−0.5)
        (ColorControl::SeparateSpecular, 0.8 - 0.1),
    ] {
        let model = LightModel {
            color_control: control,
            ..dark_model()
        };
        let scene = eye_space(model, material, vec![light]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(b.lights[0].ambient, DVec3::splat(-0.1));
        assert_close!(b.lights[0].specular, DVec3::splat(-0.5));
        assert_close!(
            front(&scene, ORIGIN, UP),
            grey(expected),
            tol = 1e-12,
            "{control:?}"
        );
    }
}

// ---------------------------------------------------------------------------
// Local viewer at the vertex
// ---------------------------------------------------------------------------

/// The eye exactly at the vertex: VP_e = 0, so ĥ = VP_pli. With VP = (1,0,1)/√2:
/// Blinn-Phong n·ĥ = 1/√2, (1/√2)² = 1/2; Phong r·VP_e = 0, so 0 with
/// shininess 2 and 0^0 = 1 with shininess 0.
#[test]
fn local_viewer_at_the_vertex() {
    let v = DVec3::new(1.0, 2.0, 3.0);
    let light = Light {
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, 1.0)))
    };
    for (model, shininess, factor) in [
        (SpecularModel::BlinnPhong, 2.0, 0.5),
        (SpecularModel::BlinnPhong, 0.0, 1.0),
        (SpecularModel::Phong, 2.0, 0.0),
        (SpecularModel::Phong, 0.0, 1.0),
    ] {
        let mut scene = eye_space(
            LightModel {
                specular_model: model,
                local_viewer: true,
                ..dark_model()
            },
            Material {
                specular: grey(0.6),
                shininess,
                ..black_material()
            },
            vec![light],
        );
        scene.lights.viewer = Viewer::Local(v);
        assert_close!(
            front_terms(&scene, v, UP).lights[0].specular,
            DVec3::splat(0.6 * factor),
            tol = 1e-12,
            "{model:?}, shininess {shininess}"
        );
    }
}

// ---------------------------------------------------------------------------
// Extreme normals
// ---------------------------------------------------------------------------

/// With normalisation on, normals of length 1e300 or 1e-300 (and the extremes
/// of f64) keep their direction. Each normal n below has the direction of
/// `unit_n`; under a light overhead the diffuse term is (unit_n·z)·0.8.
#[test]
fn huge_and_tiny_normals_keep_their_direction() {
    let material = Material {
        diffuse: grey(0.8),
        ..black_material()
    };
    let light = Light {
        diffuse: grey(1.0),
        ..black_light(LightPosition::Directional(DVec3::Z))
    };
    let scene = eye_space(dark_model(), material, vec![light]);
    for (n, unit_n) in [
        (DVec3::new(0.0, 0.0, 1e300), UP),
        (DVec3::new(0.0, 0.0, 1e-300), UP),
        (DVec3::new(0.0, 1e300, 1e300), DVec3::new(0.0, R2, R2)),
        (DVec3::new(0.0, 1e-300, 1e-300), DVec3::new(0.0, R2, R2)),
        (DVec3::new(0.0, f64::MAX, f64::MAX), DVec3::new(0.0, R2, R2)),
        (DVec3::new(0.0, 5e-324, 5e-324), DVec3::new(0.0, R2, R2)), // subnormal
        (DVec3::new(3e300, 0.0, 4e300), DVec3::new(0.6, 0.0, 0.8)),
        (DVec3::new(3e-300, 0.0, 4e-300), DVec3::new(0.6, 0.0, 0.8)),
        (DVec3::new(0.0, 0.0, -1e300), DVec3::NEG_Z),
    ] {
        assert_close!(unit_or_zero(n), unit_n, tol = 1e-15, "n = {n:?}");
        let expected = 0.8 * unit_n.z.max(0.0);
        assert_close!(
            front(&scene, ORIGIN, n),
            grey(expected),
            tol = 1e-15,
            "n = {n:?}"
        );
    }
}

// ---------------------------------------------------------------------------
// No NaN anywhere
// ---------------------------------------------------------------------------

/// Every combination of the degenerate inputs above, at once: zero and
/// extreme normals, lights at the vertex with k0 = 0, a local viewer at the
/// vertex, cones of 0 and 90 degrees with exponents 0 and 128, shininess 0 and
/// 128, both specular models, both colour controls, normalisation on and
/// off, negative light colours. Every term is finite and every colour is in
/// [0, 1].
#[test]
fn no_nan_in_degenerate_combinations() {
    let v = DVec3::new(1.0, -2.0, 3.0);
    let normals = [
        DVec3::ZERO,
        UP,
        DVec3::new(0.0, 0.0, 1e300),
        DVec3::new(0.0, 0.0, 1e-300),
        DVec3::new(1e6, -1e6, 1e6), // MAX_RAW_NORMAL
        DVec3::X,
    ];
    let positions = [
        LightPosition::Positional(v),
        LightPosition::Positional(v + DVec3::new(0.0, 0.0, 1e-9)),
        LightPosition::Positional(v + DVec3::new(1.0, 0.0, 0.0)),
        LightPosition::Positional(DVec3::splat(1e30)),
        LightPosition::Directional(DVec3::X),
        LightPosition::Directional(DVec3::Z),
    ];
    let spots = [
        Spot::default(),
        Spot {
            direction: DVec3::NEG_Z,
            exponent: 0.0,
            cutoff: 90.0,
        },
        Spot {
            direction: DVec3::NEG_Z,
            exponent: 128.0,
            cutoff: 90.0,
        },
        Spot {
            direction: DVec3::X,
            exponent: 0.0,
            cutoff: 0.0,
        },
    ];
    let viewers = [
        Viewer::Local(v),
        Viewer::Local(ORIGIN),
        Viewer::Infinite(DVec3::Z),
        Viewer::Infinite(DVec3::NEG_Z),
    ];
    let mut checked = 0;
    for &position in &positions {
        for &spot in &spots {
            for k in [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]] {
                let lights = vec![
                    Light {
                        position,
                        spot,
                        attenuation: k,
                        ambient: grey(0.3),
                        diffuse: rgb(1.0, -1.0, 0.5),
                        specular: rgb(-1.0, 1.0, 0.5),
                    },
                    Light::default(),
                ];
                for shininess in [0.0, 128.0] {
                    for specular_model in [SpecularModel::BlinnPhong, SpecularModel::Phong] {
                        for color_control in [ColorControl::Single, ColorControl::SeparateSpecular]
                        {
                            for normalize_normals in [true, false] {
                                for &viewer in &viewers {
                                    let material = Material {
                                        specular: grey(1.0),
                                        shininess,
                                        ..Material::default()
                                    };
                                    let scene = Scene {
                                        lights: light_set(
                                            LightModel {
                                                two_side: true,
                                                specular_model,
                                                color_control,
                                                normalize_normals,
                                                ..LightModel::default()
                                            },
                                            lights.clone(),
                                            viewer,
                                        ),
                                        material: SurfaceMaterial::both_sides(material),
                                    };
                                    for &n in &normals {
                                        // Raw normals are bounded by
                                        // MAX_RAW_NORMAL when used as given.
                                        if !normalize_normals
                                            && n.abs().max_element() > MAX_RAW_NORMAL
                                        {
                                            continue;
                                        }
                                        for side in [Side::Front, Side::Back] {
                                            let context =
                                                format!("{side:?}, n = {n:?}, scene = {scene:?}");
                                            let b = scene.evaluate(side, v, n);
                                            assert_finite_breakdown(&b, &context);
                                            assert!(b.unclamped().is_finite(), "{context}");
                                            let c = scene.color(side, v, n);
                                            assert_unit_color(c, &context);
                                            checked += 1;
                                        }
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    // Normalisation on: 6 normals; off: 5 (not the one of length 1e300).
    assert_eq!(checked, 6 * 4 * 3 * 2 * 2 * 2 * 4 * (6 + 5) * 2);
}

/// The edge cases of the reference, on both sides of a two-sided model,
/// never produce an out-of-range alpha either: alpha is d_cm's.
#[test]
fn alpha_survives_degenerate_input() {
    let material = Material {
        diffuse: DVec4::new(0.8, 0.8, 0.8, 0.25),
        ..Material::default()
    };
    let light = Light {
        attenuation: [0.0, 0.0, 1.0],
        ..black_light(LightPosition::Positional(ORIGIN))
    };
    let scene = eye_space(
        LightModel {
            two_side: true,
            ..LightModel::default()
        },
        material,
        vec![light],
    );
    for side in [Side::Front, Side::Back] {
        assert_eq!(scene.color(side, ORIGIN, DVec3::ZERO).w, 0.25);
    }
}
