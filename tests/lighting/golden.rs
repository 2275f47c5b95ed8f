//! Golden values: one hand-computed case per term of the lighting equation
//! and per option of the light model.
//!
//! Unless a test says otherwise the vertex is at the origin with normal +z,
//! the viewer is GL's infinite eye-space viewer (VP_e = +z), the material and
//! the lights are black except for the colours the test sets, and the global
//! ambient is zero, so that each expected value is one term of
//!
//! ```text
//! c = e_cm + a_cm·a_cs
//!   + Σ_i att_i · spot_i · [a_cm·a_cli + (n⊙VP_pli) d_cm·d_cli + f_i (n⊙ĥ_i)^s_rm s_cm·s_cli]
//! ```

use glam::{DVec3, DVec4};
use glint_lighting::{
    ColorControl, Light, LightModel, LightPosition, LightSet, Material, Side, SpecularModel, Spot,
    SurfaceMaterial, Viewer,
};

use super::support::{
    BLACK, R2, Scene, black_light, black_material, dark_model, eye_space, front, front_terms, grey,
    light_set, rgb, unit, with_lights,
};

const ORIGIN: DVec3 = DVec3::ZERO;
const UP: DVec3 = DVec3::Z;

/// A directional light (w = 0) towards `towards_light`, with only a diffuse
/// colour.
fn diffuse_light(towards_light: DVec3, diffuse: DVec4) -> Light {
    Light {
        diffuse,
        ..black_light(LightPosition::Directional(towards_light))
    }
}

// ---------------------------------------------------------------------------
// GL's defaults
// ---------------------------------------------------------------------------

/// Table 6.11/6.12 of the GL 2.1 specification: the initial material.
#[test]
fn material_default_is_gl_initial_state() {
    let m = Material::default();
    assert_eq!(m.ambient, DVec4::new(0.2, 0.2, 0.2, 1.0));
    assert_eq!(m.diffuse, DVec4::new(0.8, 0.8, 0.8, 1.0));
    assert_eq!(m.specular, DVec4::new(0.0, 0.0, 0.0, 1.0));
    assert_eq!(m.emission, DVec4::new(0.0, 0.0, 0.0, 1.0));
    assert_eq!(m.shininess, 0.0);
}

/// GL_LIGHT0's initial state: ambient (0,0,0,1), diffuse and specular
/// (1,1,1,1), position (0,0,1,0) (directional, towards +z), spot direction
/// (0,0,-1), exponent 0, cutoff 180, attenuation (1,0,0).
#[test]
fn light_default_is_gl_light0() {
    let l = Light::default();
    assert_eq!(
        l.position,
        LightPosition::Directional(DVec3::new(0.0, 0.0, 1.0))
    );
    assert_eq!(l.ambient, DVec4::new(0.0, 0.0, 0.0, 1.0));
    assert_eq!(l.diffuse, DVec4::new(1.0, 1.0, 1.0, 1.0));
    assert_eq!(l.specular, DVec4::new(1.0, 1.0, 1.0, 1.0));
    assert_eq!(l.attenuation, [1.0, 0.0, 0.0]);
    assert_eq!(l.spot.direction, DVec3::new(0.0, 0.0, -1.0));
    assert_eq!(l.spot.exponent, 0.0);
    assert_eq!(l.spot.cutoff, 180.0);
    assert!(!l.spot.is_cone());
}

/// GL's initial light model: LIGHT_MODEL_AMBIENT (0.2,0.2,0.2,1.0),
/// LOCAL_VIEWER false, TWO_SIDE false, COLOR_CONTROL SINGLE_COLOR; glint's
/// own options default to plain GL (Blinn-Phong, no attenuation clamp).
#[test]
fn light_model_default_is_gl_initial_state() {
    let m = LightModel::default();
    assert_eq!(m.ambient, DVec4::new(0.2, 0.2, 0.2, 1.0));
    assert!(!m.local_viewer);
    assert!(!m.two_side);
    assert_eq!(m.color_control, ColorControl::Single);
    assert_eq!(m.specular_model, SpecularModel::BlinnPhong);
    assert!(!m.attenuation_clamp);
    // NOT GL's initial state: GL_NORMALIZE starts disabled (section 2.11.3).
    // glint normalises by default; this pins that choice so that changing it
    // is deliberate.
    assert!(m.normalize_normals);
}

/// All defaults together, GL_LIGHT0 on a vertex facing it:
/// e_cm + a_cm·a_cs + a_cm·a_cl0 + (n⊙VP) d_cm·d_cl0 + (n⊙ĥ)^0 s_cm·s_cl0
/// = 0 + 0.2·0.2 + 0.2·0 + 1·0.8·1 + 1·0·1 = 0.84, alpha = d_cm's 1.
#[test]
fn gl_default_state_lights_a_vertex_facing_light0() {
    let scene = Scene {
        lights: light_set(
            LightModel::default(),
            vec![Light::default()],
            LightSet::eye_space_viewer(false),
        ),
        material: SurfaceMaterial {
            front: Material::default(),
            back: Material::default(),
        },
    };
    let expected = 0.2 * 0.2 + 0.8 * 1.0;
    assert_close!(
        front(&scene, ORIGIN, UP),
        DVec4::new(expected, expected, expected, 1.0)
    );
}

/// The eye-space viewers: the eye at the origin (local) or at infinity along
/// +z (section 2.14.1, v_bs false: ĥ = VP + (0, 0, 1)).
#[test]
fn eye_space_viewers() {
    assert_eq!(LightSet::eye_space_viewer(true), Viewer::Local(DVec3::ZERO));
    assert_eq!(
        LightSet::eye_space_viewer(false),
        Viewer::Infinite(DVec3::Z)
    );
}

// ---------------------------------------------------------------------------
// Terms outside the sum over lights
// ---------------------------------------------------------------------------

/// No lights, no ambient: c = e_cm, wherever the vertex is and whatever its
/// normal.
#[test]
fn emission_alone() {
    let material = Material {
        emission: rgb(0.1, 0.2, 0.3),
        ..black_material()
    };
    let scene = eye_space(dark_model(), material, vec![]);
    for (v, n) in [
        (ORIGIN, UP),
        (DVec3::new(5.0, -3.0, 2.0), DVec3::NEG_X),
        (ORIGIN, DVec3::ZERO),
    ] {
        let b = front_terms(&scene, v, n);
        assert_close!(b.emission, DVec3::new(0.1, 0.2, 0.3));
        assert_close!(b.global_ambient, DVec3::ZERO);
        assert_close!(front(&scene, v, n), DVec4::new(0.1, 0.2, 0.3, 1.0));
    }
}

/// c = a_cm·a_cs = (0.5·0.2, 0.25·0.4, 1.0·0.6) = (0.1, 0.1, 0.6).
#[test]
fn global_ambient_is_material_ambient_times_scene_ambient() {
    let model = LightModel {
        ambient: rgb(0.2, 0.4, 0.6),
        ..LightModel::default()
    };
    let material = Material {
        ambient: rgb(0.5, 0.25, 1.0),
        ..black_material()
    };
    let scene = eye_space(model, material, vec![]);
    let expected = DVec3::new(0.5 * 0.2, 0.25 * 0.4, 1.0 * 0.6);
    assert_close!(front_terms(&scene, ORIGIN, UP).global_ambient, expected);
    assert_close!(front(&scene, ORIGIN, UP), expected.extend(1.0));
}

/// No lights: c = e_cm + a_cm·a_cs and the breakdown has no light terms.
/// GL's default material and model: 0 + 0.2·0.2 = 0.04.
#[test]
fn no_lights_leaves_emission_and_global_ambient() {
    let scene = eye_space(LightModel::default(), Material::default(), vec![]);
    let b = front_terms(&scene, ORIGIN, UP);
    assert!(b.lights.is_empty());
    assert_close!(front(&scene, ORIGIN, UP), DVec4::new(0.04, 0.04, 0.04, 1.0));
}

// ---------------------------------------------------------------------------
// One light's terms
// ---------------------------------------------------------------------------

/// att·spot·a_cm·a_cli with att = spot = 1 (directional, no cone):
/// (0.4·0.5, 0.6·1.0, 0.8·0.25) = (0.2, 0.6, 0.2). The ambient term does not
/// depend on the normal: a light below the surface (VP = -z) adds it too.
#[test]
fn light_ambient_is_material_ambient_times_light_ambient() {
    let material = Material {
        ambient: rgb(0.4, 0.6, 0.8),
        ..black_material()
    };
    for towards_light in [DVec3::Z, DVec3::NEG_Z, unit(1.0, 0.0, 1.0)] {
        let light = Light {
            ambient: rgb(0.5, 1.0, 0.25),
            ..black_light(LightPosition::Directional(towards_light))
        };
        let scene = eye_space(dark_model(), material, vec![light]);
        let b = front_terms(&scene, ORIGIN, UP);
        let expected = DVec3::new(0.4 * 0.5, 0.6 * 1.0, 0.8 * 0.25);
        assert_close!(b.lights[0].ambient, expected);
        assert_close!(b.lights[0].diffuse, DVec3::ZERO);
        assert_close!(b.lights[0].specular, DVec3::ZERO);
        assert_close!(front(&scene, ORIGIN, UP), expected.extend(1.0));
    }
}

/// (n⊙VP) d_cm·d_cli with the light at 45°: VP = (1,0,1)/√2, n·VP = 1/√2;
/// d_cm·d_cli = (0.8·1, 0.6·0.5, 0.4·0.25) = (0.8, 0.3, 0.1).
#[test]
fn diffuse_at_45_degrees() {
    let material = Material {
        diffuse: rgb(0.8, 0.6, 0.4),
        ..black_material()
    };
    let light = diffuse_light(unit(1.0, 0.0, 1.0), rgb(1.0, 0.5, 0.25));
    let scene = eye_space(dark_model(), material, vec![light]);
    let expected = DVec3::new(0.8, 0.3, 0.1) * R2;
    assert_close!(front_terms(&scene, ORIGIN, UP).lights[0].diffuse, expected);
    assert_close!(front(&scene, ORIGIN, UP), expected.extend(1.0));
}

/// n⊙VP for a light overhead is 1, for a light below is max(0, -1) = 0, for a
/// light in the tangent plane 0.
#[test]
fn diffuse_follows_the_clamped_cosine() {
    let material = Material {
        diffuse: grey(0.8),
        ..black_material()
    };
    for (towards_light, n_dot_vp) in [
        (DVec3::Z, 1.0),
        (DVec3::NEG_Z, 0.0),
        (DVec3::X, 0.0),
        (unit(1.0, 0.0, -1.0), 0.0),
        // 60° from the normal: cos 60° = 1/2 (VP = (√3/2, 0, 1/2)).
        (DVec3::new(3f64.sqrt() / 2.0, 0.0, 0.5), 0.5),
    ] {
        let scene = eye_space(
            dark_model(),
            material,
            vec![diffuse_light(towards_light, grey(1.0))],
        );
        assert_close!(
            front_terms(&scene, ORIGIN, UP).lights[0].diffuse,
            DVec3::splat(0.8 * n_dot_vp),
            tol = 1e-12,
            "light towards {towards_light:?}"
        );
    }
}

/// Blinn-Phong with the infinite viewer: VP = (1,0,1)/√2, ĥ = (VP + z)/|VP + z|
/// bisects 45° and 0°, so n·ĥ = cos 22.5° and (n·ĥ)² = (1 + cos 45°)/2
/// = (1 + 1/√2)/2. s_cm·s_cli = (1, 0.5, 0.25)·0.8.
#[test]
fn specular_blinn_phong_infinite_viewer() {
    let material = Material {
        specular: rgb(1.0, 0.5, 0.25),
        shininess: 2.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(0.8),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, 1.0)))
    };
    let scene = eye_space(dark_model(), material, vec![light]);
    let expected = DVec3::new(0.8, 0.4, 0.2) * ((1.0 + R2) / 2.0);
    let b = front_terms(&scene, ORIGIN, UP);
    assert_close!(b.lights[0].specular, expected);
    assert_close!(b.lights[0].diffuse, DVec3::ZERO);
    assert_close!(front(&scene, ORIGIN, UP), expected.extend(1.0));
}

/// Local viewer at the origin, vertex at (1,0,-1): VP_e = (-1,0,1)/√2 and the
/// light at VP = (1,0,1)/√2 give ĥ = (0,0,√2)/√2 = +z, so n·ĥ = 1 and the
/// specular term is the full s_cm·s_cli = 0.5·0.8 whatever the shininess.
/// The infinite viewer at the same vertex gives cos(22.5°)^8
/// = ((1 + 1/√2)/2)^4.
#[test]
fn specular_blinn_phong_local_viewer() {
    let material = Material {
        specular: grey(0.5),
        shininess: 8.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(0.8),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, 1.0)))
    };
    let v = DVec3::new(1.0, 0.0, -1.0);

    let local = LightModel {
        local_viewer: true,
        ..dark_model()
    };
    let scene = eye_space(local, material, vec![light]);
    assert_eq!(scene.lights.viewer, Viewer::Local(DVec3::ZERO));
    assert_close!(
        front_terms(&scene, v, UP).lights[0].specular,
        DVec3::splat(0.5 * 0.8)
    );

    let infinite = eye_space(dark_model(), material, vec![light]);
    let cos_sq = (1.0 + R2) / 2.0;
    assert_close!(
        front_terms(&infinite, v, UP).lights[0].specular,
        DVec3::splat(0.5 * 0.8 * cos_sq.powi(4))
    );
}

/// A world-space viewer (any point, any direction) is used as given: with the
/// eye at (0,0,5) above the vertex at the origin, VP_e = +z and the result
/// matches the infinite viewer, (n·ĥ)² = (1 + 1/√2)/2.
#[test]
fn specular_with_a_world_space_viewer() {
    let material = Material {
        specular: grey(1.0),
        shininess: 2.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, 1.0)))
    };
    let mut scene = eye_space(dark_model(), material, vec![light]);
    scene.lights.viewer = Viewer::Local(DVec3::new(0.0, 0.0, 5.0));
    assert_close!(
        front_terms(&scene, ORIGIN, UP).lights[0].specular,
        DVec3::splat((1.0 + R2) / 2.0)
    );
}

/// f_i = 0 when n·VP ≤ 0. The light below at VP = (1,0,-1)/√2 with the
/// infinite viewer has ĥ ∝ (1/√2, 0, 1 − 1/√2), so n·ĥ > 0 and, without f_i,
/// shininess 0 would give the full specular colour. With f_i: nothing.
#[test]
fn no_specular_when_the_light_is_behind() {
    let material = Material {
        specular: grey(1.0),
        diffuse: grey(1.0),
        shininess: 0.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(1.0),
        diffuse: grey(1.0),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, -1.0)))
    };
    for shininess in [0.0, 1.0] {
        let scene = eye_space(
            dark_model(),
            Material {
                shininess,
                ..material
            },
            vec![light],
        );
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(b.lights[0].specular, DVec3::ZERO);
        assert_close!(b.lights[0].diffuse, DVec3::ZERO);
        assert_close!(front(&scene, ORIGIN, UP), BLACK);
    }
    // The same light above (VP = (1,0,1)/√2): f_i = 1 and (n·ĥ)^0 = 1.
    let above = Light {
        position: LightPosition::Directional(unit(1.0, 0.0, 1.0)),
        ..light
    };
    let scene = eye_space(dark_model(), material, vec![above]);
    assert_close!(
        front_terms(&scene, ORIGIN, UP).lights[0].specular,
        DVec3::ONE
    );
}

// ---------------------------------------------------------------------------
// Attenuation
// ---------------------------------------------------------------------------

/// A positional light at (0,0,2): d = |P − V| = 2, VP = +z, n·VP = 1.
/// att = 1/(k0 + k1·d + k2·d²).
#[test]
fn attenuation_of_a_positional_light() {
    let material = Material {
        ambient: grey(0.4),
        diffuse: grey(0.8),
        ..black_material()
    };
    for (k, att) in [
        ([1.0, 0.5, 0.25], 1.0 / (1.0 + 0.5 * 2.0 + 0.25 * 4.0)), // 1/3
        ([2.0, 0.0, 0.0], 1.0 / 2.0),
        ([0.0, 1.0, 0.0], 1.0 / 2.0),
        ([0.0, 0.0, 1.0], 1.0 / 4.0),
    ] {
        let light = Light {
            ambient: grey(0.5),
            diffuse: grey(1.0),
            attenuation: k,
            ..black_light(LightPosition::Positional(DVec3::new(0.0, 0.0, 2.0)))
        };
        let scene = eye_space(dark_model(), material, vec![light]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(b.lights[0].attenuation, att, tol = 1e-15, "k = {k:?}");
        // att·a_cm·a_cli = att·0.4·0.5; att·(n·VP)·d_cm·d_cli = att·1·0.8·1.
        assert_close!(b.lights[0].ambient, DVec3::splat(att * 0.4 * 0.5));
        assert_close!(b.lights[0].diffuse, DVec3::splat(att * 0.8));
        assert_close!(
            front(&scene, ORIGIN, UP),
            DVec4::new(1.0, 1.0, 1.0, 0.0) * (att * (0.2 + 0.8)) + DVec4::W
        );
    }
}

/// A positional light at (3,0,3): d = 3√2, d² = 18, VP = (1,0,1)/√2.
/// k = (1, 0.5, 1): att = 1/(1 + 0.5·3√2 + 18); diffuse = att·(1/√2)·0.8.
#[test]
fn attenuation_at_45_degrees() {
    let material = Material {
        diffuse: grey(0.8),
        ..black_material()
    };
    let light = Light {
        diffuse: grey(1.0),
        attenuation: [1.0, 0.5, 1.0],
        ..black_light(LightPosition::Positional(DVec3::new(3.0, 0.0, 3.0)))
    };
    let scene = eye_space(dark_model(), material, vec![light]);
    let att = 1.0 / (1.0 + 0.5 * 3.0 * 2f64.sqrt() + 18.0);
    let b = front_terms(&scene, ORIGIN, UP);
    assert_close!(b.lights[0].attenuation, att);
    assert_close!(b.lights[0].diffuse, DVec3::splat(att * R2 * 0.8));
}

/// att_i = 1 when P_pli has w = 0, whatever k0, k1, k2.
#[test]
fn attenuation_is_ignored_for_directional_lights() {
    let material = Material {
        diffuse: grey(0.8),
        ..black_material()
    };
    for k in [[0.0, 3.0, 7.0], [5.0, 0.0, 0.0], [0.0, 0.0, 0.5]] {
        let light = Light {
            attenuation: k,
            ..diffuse_light(DVec3::Z, grey(1.0))
        };
        let scene = eye_space(dark_model(), material, vec![light]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(b.lights[0].attenuation, 1.0);
        assert_close!(b.lights[0].diffuse, DVec3::splat(0.8));
    }
}

/// attenuation_clamp: att = min(att, 1). A light at (0,0,1) (d = 1) with
/// k = (0.25,0,0) has att = 4, clamped to 1; k = (1,1,0) gives 1/2, which the
/// clamp leaves alone.
#[test]
fn attenuation_clamp() {
    let material = Material {
        diffuse: grey(0.1),
        ..black_material()
    };
    for (k, clamp, att) in [
        ([0.25, 0.0, 0.0], false, 4.0),
        ([0.25, 0.0, 0.0], true, 1.0),
        ([1.0, 1.0, 0.0], false, 0.5),
        ([1.0, 1.0, 0.0], true, 0.5),
    ] {
        let light = Light {
            attenuation: k,
            ..diffuse_light(DVec3::Z, grey(1.0))
        };
        let light = Light {
            position: LightPosition::Positional(DVec3::new(0.0, 0.0, 1.0)),
            ..light
        };
        let model = LightModel {
            attenuation_clamp: clamp,
            ..dark_model()
        };
        let scene = eye_space(model, material, vec![light]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(
            b.lights[0].attenuation,
            att,
            tol = 1e-15,
            "k = {k:?}, clamp {clamp}"
        );
        // att·(n·VP = 1)·0.1·1
        assert_close!(b.lights[0].diffuse, DVec3::splat(att * 0.1));
    }
}

/// A homogeneous light position (0,0,4,2) is the point (0,0,4)/2 = (0,0,2):
/// with k = (0,1,0), att = 1/d = 1/2 (not the 1/4 of the undivided (0,0,4)).
///
/// The division by w happens where a request is validated into a
/// `LightPosition` (outside `glint::lighting`); this test pins the numbers
/// that division must produce.
#[test]
fn homogeneous_light_position_is_divided_by_w() {
    let gl_position = DVec4::new(0.0, 0.0, 4.0, 2.0);
    let point = gl_position.truncate() / gl_position.w;
    let light = Light {
        attenuation: [0.0, 1.0, 0.0],
        ..diffuse_light(DVec3::Z, grey(1.0))
    };
    let light = Light {
        position: LightPosition::Positional(point),
        ..light
    };
    let material = Material {
        diffuse: grey(0.8),
        ..black_material()
    };
    let scene = eye_space(dark_model(), material, vec![light]);
    let b = front_terms(&scene, ORIGIN, UP);
    assert_close!(b.lights[0].attenuation, 1.0 / 2.0);
    assert_close!(b.lights[0].diffuse, DVec3::splat(0.8 / 2.0));
}

// ---------------------------------------------------------------------------
// Spotlights
// ---------------------------------------------------------------------------

/// A spotlight at (0,0,4) pointing down (ŝ = -z), cutoff 60° (cos = 1/2).
fn spotlight(exponent: f64, cutoff: f64) -> Light {
    Light {
        ambient: grey(1.0),
        diffuse: grey(1.0),
        spot: Spot {
            direction: DVec3::NEG_Z,
            exponent,
            cutoff,
        },
        ..black_light(LightPosition::Positional(DVec3::new(0.0, 0.0, 4.0)))
    }
}

/// Inside the cone:
/// - V at the origin, on the axis: P_pli V = -z, ŝ·(-z) = 1, spot = 1^e = 1;
///   n·VP = 1.
/// - V = (4,0,0): P_pli V = (4,0,-4)/(4√2), cos = 1/√2 (45° < 60°),
///   spot = (1/√2)^e; VP = (-1,0,1)/√2, n·VP = 1/√2.
///
/// Outside: V = (8,0,0): P_pli V = (8,0,-4)/(4√5), cos = 1/√5 < 1/2: spot = 0,
/// and the ambient term goes too.
#[test]
fn spot_cutoff_inside_and_outside() {
    let material = Material {
        ambient: grey(0.5),
        diffuse: grey(0.8),
        ..black_material()
    };
    let scene = eye_space(dark_model(), material, vec![spotlight(2.0, 60.0)]);

    let on_axis = front_terms(&scene, ORIGIN, UP);
    assert_close!(on_axis.lights[0].spot, 1.0);
    assert_close!(on_axis.lights[0].diffuse, DVec3::splat(0.8));

    let at_45 = front_terms(&scene, DVec3::new(4.0, 0.0, 0.0), UP);
    let spot = R2 * R2; // (1/√2)²
    assert_close!(at_45.lights[0].spot, spot);
    assert_close!(at_45.lights[0].ambient, DVec3::splat(spot * 0.5));
    assert_close!(at_45.lights[0].diffuse, DVec3::splat(spot * R2 * 0.8));

    let outside = front_terms(&scene, DVec3::new(8.0, 0.0, 0.0), UP);
    assert_close!(outside.lights[0].spot, 0.0);
    assert_close!(outside.lights[0].ambient, DVec3::ZERO);
    assert_close!(outside.lights[0].diffuse, DVec3::ZERO);
    assert_close!(front(&scene, DVec3::new(8.0, 0.0, 0.0), UP), BLACK);

    // A 30° cone leaves the vertex at 45° outside.
    let narrow = eye_space(dark_model(), material, vec![spotlight(2.0, 30.0)]);
    assert_close!(
        front_terms(&narrow, DVec3::new(4.0, 0.0, 0.0), UP).lights[0].spot,
        0.0
    );
}

/// spot = (P_pli V ⊙ ŝ)^s_rli at 45° inside a 60° cone: (1/√2)^e.
#[test]
fn spot_exponent() {
    let v = DVec3::new(4.0, 0.0, 0.0);
    for (exponent, spot) in [
        (0.0, 1.0),
        (1.0, R2),
        (2.0, 0.5),
        (3.0, 0.5 * R2),
        (10.0, 1.0 / 32.0), // (1/√2)^10 = 2^-5
    ] {
        let scene = eye_space(
            dark_model(),
            black_material(),
            vec![spotlight(exponent, 60.0)],
        );
        assert_close!(
            front_terms(&scene, v, UP).lights[0].spot,
            spot,
            tol = 1e-12,
            "exponent {exponent}"
        );
    }
}

/// A directional light (w = 0) with a cone: P_pli V is the negated light
/// direction, here -z for the light towards +z, the same at every vertex.
/// With ŝ = (1,0,-1)/√2: ŝ·(-z) = 1/√2 (45°).
/// - cutoff 60, exponent 2: spot = 1/2 everywhere, scaling every term;
/// - cutoff 30: spot = 0 everywhere;
/// - ŝ = -z: spot = 1.
#[test]
fn directional_light_with_a_spot() {
    let material = Material {
        ambient: grey(0.1),
        diffuse: grey(0.8),
        ..black_material()
    };
    let light = |direction: DVec3, cutoff: f64| Light {
        ambient: grey(1.0),
        diffuse: grey(1.0),
        spot: Spot {
            direction,
            exponent: 2.0,
            cutoff,
        },
        ..black_light(LightPosition::Directional(DVec3::Z))
    };
    for v in [
        ORIGIN,
        DVec3::new(5.0, -7.0, 3.0),
        DVec3::new(-100.0, 0.0, -50.0),
    ] {
        for (direction, cutoff, spot) in [
            (unit(1.0, 0.0, -1.0), 60.0, 0.5),
            (unit(1.0, 0.0, -1.0), 30.0, 0.0),
            (DVec3::NEG_Z, 30.0, 1.0),
        ] {
            let scene = eye_space(dark_model(), material, vec![light(direction, cutoff)]);
            let b = front_terms(&scene, v, UP);
            let context = format!("vertex {v:?}, ŝ {direction:?}, cutoff {cutoff}");
            assert_close!(b.lights[0].spot, spot, tol = 1e-12, "{context}");
            assert_close!(b.lights[0].attenuation, 1.0, tol = 1e-12, "{context}");
            // spot·(a_cm·a_cli + (n·VP = 1)·d_cm·d_cli) = spot·(0.1 + 0.8).
            assert_close!(
                front(&scene, v, UP),
                DVec4::new(1.0, 1.0, 1.0, 0.0) * (spot * (0.1 + 0.8)) + DVec4::W,
                tol = 1e-12,
                "{context}"
            );
        }
    }
}

// ---------------------------------------------------------------------------
// Two-sided lighting
// ---------------------------------------------------------------------------

/// With two-sided lighting the back colour uses the back material and -n.
/// The light below (VP = -z) misses the front (n·VP = -1 → 0) and lights the
/// back fully (-n·VP = 1): front black, back = d_bm·d_cli = (0, 0, 1) with
/// the back diffuse alpha 0.5. At 45° below: back diffuse 1/√2.
#[test]
fn two_sided_lighting_uses_the_back_material_and_the_negated_normal() {
    let model = LightModel {
        two_side: true,
        ..dark_model()
    };
    let scene = |towards_light: DVec3| Scene {
        lights: light_set(
            model,
            vec![diffuse_light(towards_light, grey(1.0))],
            LightSet::eye_space_viewer(false),
        ),
        material: SurfaceMaterial {
            front: Material {
                diffuse: rgb(1.0, 0.0, 0.0),
                ..black_material()
            },
            back: Material {
                diffuse: DVec4::new(0.0, 0.0, 1.0, 0.5),
                ..black_material()
            },
        },
    };

    let below = scene(DVec3::NEG_Z);
    assert_close!(front(&below, ORIGIN, UP), BLACK);
    assert_close!(
        below.color(Side::Back, ORIGIN, UP),
        DVec4::new(0.0, 0.0, 1.0, 0.5)
    );

    let below_45 = scene(unit(1.0, 0.0, -1.0));
    assert_close!(
        below_45.evaluate(Side::Back, ORIGIN, UP).lights[0].diffuse,
        DVec3::new(0.0, 0.0, R2)
    );

    // The light above lights the front, not the back.
    let above = scene(DVec3::Z);
    assert_close!(front(&above, ORIGIN, UP), rgb(1.0, 0.0, 0.0));
    assert_close!(
        above.color(Side::Back, ORIGIN, UP),
        DVec4::new(0.0, 0.0, 0.0, 0.5)
    );
}

/// The back side's specular also uses -n: a viewer and a light both below
/// (VP_e = VP = -z) give ĥ = -z, so the back gets (-n·ĥ)^s = 1, the front
/// f_i = 0.
#[test]
fn two_sided_specular() {
    let material = Material {
        specular: grey(0.5),
        shininess: 20.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(DVec3::NEG_Z))
    };
    let scene = Scene {
        lights: light_set(
            LightModel {
                two_side: true,
                ..dark_model()
            },
            vec![light],
            Viewer::Infinite(DVec3::NEG_Z),
        ),
        material: SurfaceMaterial::both_sides(material),
    };
    assert_close!(
        scene.evaluate(Side::Back, ORIGIN, UP).lights[0].specular,
        DVec3::splat(0.5)
    );
    assert_close!(
        scene.evaluate(Side::Front, ORIGIN, UP).lights[0].specular,
        DVec3::ZERO
    );
}

// ---------------------------------------------------------------------------
// Colour sum and clamping
// ---------------------------------------------------------------------------

/// A light overhead: n·VP = 1 and ĥ = +z, n·ĥ = 1, so the primary colour is
/// d_cli = (-0.5, 1.5, 0.25) and the secondary s_cli = (0.7, -0.6, 0.5)
/// (white material).
/// - single colour: clamp(p + s) = clamp(0.2, 0.9, 0.75) = (0.2, 0.9, 0.75);
/// - separate specular: clamp(clamp(p) + clamp(s))
///   = clamp((0, 1, 0.25) + (0.7, 0, 0.5)) = (0.7, 1, 0.75).
#[test]
fn separate_specular_colour_versus_single_colour() {
    let material = Material {
        diffuse: grey(1.0),
        specular: grey(1.0),
        shininess: 10.0,
        ..black_material()
    };
    let light = Light {
        diffuse: rgb(-0.5, 1.5, 0.25),
        specular: rgb(0.7, -0.6, 0.5),
        ..black_light(LightPosition::Directional(DVec3::Z))
    };
    for (control, expected) in [
        (ColorControl::Single, rgb(0.2, 0.9, 0.75)),
        (ColorControl::SeparateSpecular, rgb(0.7, 1.0, 0.75)),
    ] {
        let model = LightModel {
            color_control: control,
            ..dark_model()
        };
        let scene = eye_space(model, material, vec![light]);
        let b = front_terms(&scene, ORIGIN, UP);
        assert_close!(b.primary(), DVec3::new(-0.5, 1.5, 0.25));
        assert_close!(b.secondary(), DVec3::new(0.7, -0.6, 0.5));
        assert_close!(
            front(&scene, ORIGIN, UP),
            expected,
            tol = 1e-12,
            "{control:?}"
        );
    }
}

/// With non-negative terms above 1 both controls clamp to 1: primary 0.8 +
/// secondary 0.6 → 1 either way.
#[test]
fn separate_specular_saturates_like_single_colour() {
    let material = Material {
        diffuse: grey(0.8),
        specular: grey(0.6),
        ..black_material()
    };
    let light = Light {
        diffuse: grey(1.0),
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(DVec3::Z))
    };
    for control in [ColorControl::Single, ColorControl::SeparateSpecular] {
        let model = LightModel {
            color_control: control,
            ..dark_model()
        };
        let scene = eye_space(model, material, vec![light]);
        assert_close!(front(&scene, ORIGIN, UP), grey(1.0));
    }
}

/// Each channel is clamped to [0, 1]: a light overhead with d_cli = (2, -1,
/// 0.5) on a white diffuse material sums to (2, -1, 0.5) → (1, 0, 0.5).
#[test]
fn colour_is_clamped_to_unit_range() {
    let material = Material {
        diffuse: grey(1.0),
        ..black_material()
    };
    let scene = eye_space(
        dark_model(),
        material,
        vec![diffuse_light(DVec3::Z, rgb(2.0, -1.0, 0.5))],
    );
    let b = front_terms(&scene, ORIGIN, UP);
    assert_close!(b.unclamped(), DVec3::new(2.0, -1.0, 0.5));
    assert!(b.was_clamped());
    assert_close!(front(&scene, ORIGIN, UP), rgb(1.0, 0.0, 0.5));
}

/// The alpha of the lit colour is d_cm's alpha (0.3), whatever the other
/// alphas and whatever the light; the back side takes d_bm's (0.6). Alpha is
/// clamped to [0, 1] like the other channels.
#[test]
fn alpha_is_the_diffuse_alpha() {
    let material = Material {
        ambient: DVec4::new(0.2, 0.2, 0.2, 0.9),
        diffuse: DVec4::new(0.8, 0.8, 0.8, 0.3),
        specular: DVec4::new(0.5, 0.5, 0.5, 0.1),
        emission: DVec4::new(0.1, 0.1, 0.1, 0.7),
        shininess: 5.0,
    };
    let model = LightModel {
        ambient: DVec4::new(0.2, 0.2, 0.2, 0.6),
        two_side: true,
        ..LightModel::default()
    };
    let light = Light {
        ambient: DVec4::new(0.1, 0.1, 0.1, 0.5),
        diffuse: DVec4::new(1.0, 1.0, 1.0, 0.25),
        specular: DVec4::new(1.0, 1.0, 1.0, 0.0),
        ..Light::default()
    };
    let mut scene = eye_space(model, material, vec![light]);
    scene.material.back.diffuse.w = 0.6;
    assert_close!(front(&scene, ORIGIN, UP).w, 0.3);
    assert_close!(scene.color(Side::Back, ORIGIN, UP).w, 0.6);
    scene.lights = with_lights(&scene.lights, vec![]);
    assert_close!(front(&scene, ORIGIN, UP).w, 0.3);

    scene.material.front.diffuse.w = 1.5;
    assert_close!(front(&scene, ORIGIN, UP).w, 1.0);
    scene.material.front.diffuse.w = -0.5;
    assert_close!(front(&scene, ORIGIN, UP).w, 0.0);
}

// ---------------------------------------------------------------------------
// Variants glint offers
// ---------------------------------------------------------------------------

/// Phong: r = 2(n·VP)n − VP. With VP = (1,0,1)/√2 and n = z:
/// r = (2/√2)z − VP = (-1/√2, 0, 1/√2).
/// - infinite viewer (+z): r·VP_e = 1/√2, (1/√2)² = 1/2 (Blinn-Phong gives
///   (1 + 1/√2)/2 here);
/// - local viewer at the origin, vertex (1,0,-1): VP_e = (-1,0,1)/√2 = r,
///   r·VP_e = 1: full specular.
#[test]
fn phong_specular() {
    let material = Material {
        specular: grey(0.6),
        shininess: 2.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, 1.0)))
    };
    let phong = LightModel {
        specular_model: SpecularModel::Phong,
        ..dark_model()
    };

    let infinite = eye_space(phong, material, vec![light]);
    assert_close!(
        front_terms(&infinite, ORIGIN, UP).lights[0].specular,
        DVec3::splat(0.6 * 0.5)
    );
    let blinn = eye_space(dark_model(), material, vec![light]);
    assert_close!(
        front_terms(&blinn, ORIGIN, UP).lights[0].specular,
        DVec3::splat(0.6 * (1.0 + R2) / 2.0)
    );

    let local = eye_space(
        LightModel {
            local_viewer: true,
            ..phong
        },
        material,
        vec![light],
    );
    assert_close!(
        front_terms(&local, DVec3::new(1.0, 0.0, -1.0), UP).lights[0].specular,
        DVec3::splat(0.6)
    );
}

/// Phong keeps f_i: the light below at VP = (1,0,-1)/√2 reflects to
/// r = 2(-1/√2)z − VP = (-1/√2, 0, -1/√2); a viewer there (r·VP_e = 1) would
/// see a full highlight without f_i, and sees none.
#[test]
fn phong_has_no_specular_when_the_light_is_behind() {
    let material = Material {
        specular: grey(1.0),
        shininess: 1.0,
        ..black_material()
    };
    let light = Light {
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(unit(1.0, 0.0, -1.0)))
    };
    let mut scene = eye_space(
        LightModel {
            specular_model: SpecularModel::Phong,
            ..dark_model()
        },
        material,
        vec![light],
    );
    scene.lights.viewer = Viewer::Infinite(unit(-1.0, 0.0, -1.0));
    assert_close!(
        front_terms(&scene, ORIGIN, UP).lights[0].specular,
        DVec3::ZERO
    );
}

/// A normal (0,0,2) of length 2 under a light overhead (VP = ĥ = +z):
/// - normalize on: n·VP = n·ĥ = 1: diffuse 0.25, specular 0.1·1³;
/// - normalize off: n·VP = n·ĥ = 2: diffuse 2·0.25 = 0.5, specular
///   0.1·2³ = 0.8.
#[test]
fn normalize_normals_on_and_off() {
    let material = Material {
        diffuse: grey(0.25),
        specular: grey(0.1),
        shininess: 3.0,
        ..black_material()
    };
    let light = Light {
        diffuse: grey(1.0),
        specular: grey(1.0),
        ..black_light(LightPosition::Directional(DVec3::Z))
    };
    let n = DVec3::new(0.0, 0.0, 2.0);
    for (normalize, n_dot, specular) in [(true, 1.0, 0.1), (false, 2.0, 0.1 * 8.0)] {
        let model = LightModel {
            normalize_normals: normalize,
            ..dark_model()
        };
        let scene = eye_space(model, material, vec![light]);
        let b = front_terms(&scene, ORIGIN, n);
        assert_close!(b.lights[0].diffuse, DVec3::splat(n_dot * 0.25));
        assert_close!(b.lights[0].specular, DVec3::splat(specular));
    }
}

/// Several lights add: GL_LIGHT0 overhead (diffuse 0.8·1) plus a red light at
/// 60° (n·VP = 1/2, diffuse 0.8·(1,0,0)·1/2) plus the global ambient 0.2·0.2:
/// (0.04 + 0.8 + 0.4, 0.04 + 0.8, 0.04 + 0.8) → clamped red.
#[test]
fn lights_add_up() {
    let red = diffuse_light(DVec3::new(3f64.sqrt() / 2.0, 0.0, 0.5), rgb(1.0, 0.0, 0.0));
    let scene = eye_space(
        LightModel::default(),
        Material::default(),
        vec![Light::default(), red],
    );
    let b = front_terms(&scene, ORIGIN, UP);
    assert_close!(
        b.unclamped(),
        DVec3::new(0.04 + 0.8 + 0.4, 0.04 + 0.8, 0.04 + 0.8)
    );
    assert_close!(front(&scene, ORIGIN, UP), rgb(1.0, 0.84, 0.84));
}
