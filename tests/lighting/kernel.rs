//! The f32 `Kernel` measured against the f64 reference: every channel of
//! every vertex within the documented bound of its tier (1e-5 for
//! `accurate`, 1/512 for `fast`), and the visibility masks the renderer's
//! shadows use.

use glam::{DVec3, DVec4};
use glint::scene::{ShadeScene, TermsDetail};
use glint_lighting::kernel::{Colors, Kernel, StateKey, Tier};
use glint_lighting::{
    ColorControl, Light, LightModel, LightPosition, LightSet, Material, Precision, Side,
    SpecularModel, Spot, SurfaceMaterial, Viewer,
};

use super::support::{
    FAST_TOL, R2, Scene, TIERS, assert_kernel_matches_reference, black_light, black_material,
    dark_model, eye_space, grey, light_set, rgb, unit,
};

/// A 5×5 grid of vertices in the plane z = `z` over [-2, 2]², each with one
/// of a handful of normals (unit, tilted, below the surface).
fn grid(z: f64) -> (Vec<DVec3>, Vec<DVec3>) {
    let normals = [
        DVec3::Z,
        unit(1.0, 0.0, 1.0),
        unit(-1.0, 2.0, 3.0),
        unit(0.0, -1.0, 0.2),
        DVec3::NEG_Z,
        unit(3.0, 3.0, -1.0),
        DVec3::X,
    ];
    let mut positions = Vec::new();
    let mut ns = Vec::new();
    for i in 0..5 {
        for j in 0..5 {
            positions.push(DVec3::new(i as f64 - 2.0, j as f64 - 2.0, z));
            ns.push(normals[(i * 5 + j) % normals.len()]);
        }
    }
    (positions, ns)
}

/// Lights of every kind: directional, positional with attenuation (one with
/// att > 1), a spotlight, a directional spotlight, and a light with negative
/// colours.
fn assorted_lights() -> Vec<Light> {
    vec![
        Light::default(),
        Light {
            position: LightPosition::Directional(unit(1.0, -1.0, 2.0)),
            ambient: grey(0.1),
            diffuse: rgb(0.3, 0.6, 0.9),
            specular: rgb(0.9, 0.6, 0.3),
            ..Light::default()
        },
        Light {
            position: LightPosition::Positional(DVec3::new(1.0, 2.0, 3.0)),
            ambient: grey(0.2),
            diffuse: rgb(1.0, 0.5, 0.0),
            specular: grey(1.0),
            attenuation: [1.0, 0.2, 0.05],
            spot: Spot::default(),
        },
        Light {
            position: LightPosition::Positional(DVec3::new(0.0, 0.0, 4.0)),
            ambient: grey(0.3),
            diffuse: grey(0.7),
            specular: grey(0.7),
            attenuation: [0.5, 0.0, 0.1],
            spot: Spot {
                direction: unit(0.1, 0.0, -1.0),
                exponent: 8.0,
                cutoff: 40.0,
            },
        },
        Light {
            position: LightPosition::Directional(DVec3::Z),
            ambient: grey(0.05),
            diffuse: grey(0.5),
            specular: grey(0.5),
            attenuation: [1.0, 0.0, 0.0],
            spot: Spot {
                direction: unit(1.0, 0.0, -1.0),
                exponent: 2.0,
                cutoff: 60.0,
            },
        },
        // Weakly attenuated (att up to 4 near the grid), so that
        // `attenuation_clamp` matters. (Not at (0.5, -0.5, 1): that puts
        // the vertex (2, 1, 0.5) with normal (-1, 2, 3)/√14 exactly in
        // grazing light, where f_i jumps and f32 may decide either way.)
        Light {
            position: LightPosition::Positional(DVec3::new(0.3, -0.7, 1.1)),
            ambient: grey(0.02),
            diffuse: rgb(0.15, 0.1, 0.05),
            specular: grey(0.1),
            attenuation: [0.25, 0.0, 0.05],
            spot: Spot::default(),
        },
        Light {
            position: LightPosition::Positional(DVec3::new(-3.0, 1.0, 1.0)),
            ambient: grey(-0.05),
            diffuse: rgb(-0.4, 0.2, -0.1),
            specular: rgb(0.2, -0.3, 0.1),
            attenuation: [1.0, 0.5, 0.0],
            spot: Spot::default(),
        },
    ]
}

fn shiny() -> Material {
    Material {
        ambient: rgb(0.2, 0.3, 0.1),
        diffuse: DVec4::new(0.6, 0.5, 0.4, 0.75),
        specular: grey(0.8),
        emission: rgb(0.05, 0.0, 0.02),
        shininess: 24.0,
    }
}

#[test]
fn kernel_matches_reference_on_gl_defaults() {
    let scene = eye_space(
        LightModel::default(),
        Material::default(),
        vec![Light::default()],
    );
    let (positions, normals) = grid(0.0);
    assert_kernel_matches_reference(&scene, &positions, &normals);
}

#[test]
fn kernel_matches_reference_with_assorted_lights() {
    for local_viewer in [false, true] {
        let model = LightModel {
            local_viewer,
            ..LightModel::default()
        };
        let scene = eye_space(model, shiny(), assorted_lights());
        for z in [0.0, -3.0] {
            let (positions, normals) = grid(z);
            assert_kernel_matches_reference(&scene, &positions, &normals);
        }
    }
}

/// Every option of the light model at once, in both states, with a back
/// material that differs from the front.
#[test]
fn kernel_matches_reference_for_every_model_option() {
    let (positions, normals) = grid(-1.0);
    for specular_model in [SpecularModel::BlinnPhong, SpecularModel::Phong] {
        for color_control in [ColorControl::Single, ColorControl::SeparateSpecular] {
            for (two_side, attenuation_clamp, normalize_normals) in [
                (false, false, true),
                (true, true, true),
                (true, false, false),
                (false, true, false),
            ] {
                let model = LightModel {
                    ambient: rgb(0.1, 0.2, 0.3),
                    local_viewer: two_side,
                    two_side,
                    color_control,
                    specular_model,
                    attenuation_clamp,
                    normalize_normals,
                };
                let mut scene = eye_space(model, shiny(), assorted_lights());
                scene.material.back = Material {
                    diffuse: DVec4::new(0.1, 0.9, 0.2, 0.5),
                    shininess: 3.0,
                    ..shiny()
                };
                // Normals of lengths other than 1 matter when they are not
                // normalised.
                let scaled: Vec<DVec3> = normals
                    .iter()
                    .enumerate()
                    .map(|(i, n)| *n * [1.0, 0.5, 1.5][i % 3])
                    .collect();
                assert_kernel_matches_reference(&scene, &positions, &scaled);
            }
        }
    }
}

/// World-space viewers: a local eye at an arbitrary point and an infinite
/// viewer along an arbitrary direction.
#[test]
fn kernel_matches_reference_with_world_space_viewers() {
    let (positions, normals) = grid(0.5);
    for viewer in [
        Viewer::Local(DVec3::new(3.0, -4.0, 10.0)),
        Viewer::Local(DVec3::new(0.0, 0.0, 0.5)), // on a vertex of the grid
        Viewer::Infinite(unit(1.0, 1.0, 1.0)),
    ] {
        let mut scene = eye_space(LightModel::default(), shiny(), assorted_lights());
        scene.lights.viewer = viewer;
        assert_kernel_matches_reference(&scene, &positions, &normals);
    }
}

/// The degenerate inputs of the edge-case tests, chosen so that f32 makes
/// the same decisions as f64 (exact geometry): zero normal, light at a vertex
/// with k0 = 0 (the attenuation cap), local viewer at a vertex, a 90° cone
/// with vertices behind it and in its plane, grazing light, shininess 0.
#[test]
fn kernel_matches_reference_on_degenerate_input() {
    let positions = vec![
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, -3.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 2.0),
        DVec3::new(1.0, 1.0, 1.0),
    ];
    let normals = vec![
        DVec3::ZERO,
        DVec3::Z,
        DVec3::Z,
        DVec3::new(0.0, 0.0, 1e300),
        DVec3::new(0.0, 1e-300, 1e-300),
    ];
    let material = Material {
        ambient: grey(0.2),
        diffuse: grey(0.5),
        specular: grey(0.5),
        emission: grey(0.01),
        shininess: 0.0,
    };
    let lights = vec![
        // At the vertex at the origin, k0 = 0.
        Light {
            ambient: grey(1e-12),
            attenuation: [0.0, 0.0, 1.0],
            ..Light::default()
        },
        // 90° cone at the origin pointing down, exponent 0.
        Light {
            ambient: grey(0.1),
            spot: Spot {
                direction: DVec3::NEG_Z,
                exponent: 0.0,
                cutoff: 90.0,
            },
            ..black_light(LightPosition::Positional(DVec3::ZERO))
        },
        // (The 0° cone has its own test, `kernel_cutoff_0_lights_the_axis`.)
        // Grazing the +z normals.
        Light {
            diffuse: grey(0.4),
            specular: grey(0.4),
            ..black_light(LightPosition::Directional(DVec3::X))
        },
    ];
    for viewer in [
        Viewer::Local(DVec3::ZERO),
        Viewer::Local(DVec3::new(1.0, 1.0, 1.0)),
    ] {
        for specular_model in [SpecularModel::BlinnPhong, SpecularModel::Phong] {
            let model = LightModel {
                specular_model,
                two_side: true,
                ..LightModel::default()
            };
            let mut scene = eye_space(model, material, lights.clone());
            scene.lights.lights_mut()[0].position = LightPosition::Positional(positions[0]);
            scene.lights.viewer = viewer;
            assert_kernel_matches_reference(&scene, &positions, &normals);
        }
    }
}

/// Vertices and a positional light near (1e7, 1e7, 1e7), one unit apart: in
/// f32 the coordinates alone are 1-ulp = 1 apart, so only recentring on the
/// batch keeps the light's direction. Includes a local viewer near them and
/// a spotlight aimed along the batch.
#[test]
fn kernel_matches_reference_at_huge_coordinates() {
    let base = DVec3::splat(1e7);
    let light = Light {
        position: LightPosition::Positional(base + DVec3::Z),
        ambient: grey(0.1),
        diffuse: grey(0.8),
        specular: grey(0.8),
        attenuation: [1.0, 0.5, 0.25],
        spot: Spot::default(),
    };
    let spotlight = Light {
        position: LightPosition::Positional(base + DVec3::new(-1.0, 0.0, 0.5)),
        diffuse: rgb(0.5, 0.2, 0.1),
        specular: grey(0.3),
        spot: Spot {
            direction: unit(1.0, 0.0, -0.5),
            exponent: 4.0,
            cutoff: 45.0,
        },
        ..black_light(LightPosition::Directional(DVec3::Z))
    };
    let material = Material {
        specular: grey(0.6),
        shininess: 32.0,
        ..Material::default()
    };
    let offsets = [
        DVec3::ZERO,
        DVec3::new(0.25, 0.0, 0.0),
        DVec3::new(-0.5, 0.5, 0.0),
        DVec3::new(0.0, -0.75, 0.125),
        DVec3::new(0.3, 0.2, -0.1),
    ];
    let normals = [
        DVec3::Z,
        unit(1.0, 0.0, 1.0),
        unit(-1.0, 1.0, 2.0),
        unit(0.0, -1.0, 3.0),
        unit(0.2, 0.1, 1.0),
    ];
    for local_viewer in [false, true] {
        let model = LightModel {
            local_viewer,
            ..LightModel::default()
        };
        let mut scene = eye_space(model, material, vec![light, spotlight]);
        if local_viewer {
            scene.lights.viewer = Viewer::Local(base + DVec3::new(0.5, -0.5, 2.0));
        }
        // The whole batch, and each vertex alone (then the centre is the
        // vertex itself).
        let positions: Vec<DVec3> = offsets.iter().map(|o| base + *o).collect();
        assert_kernel_matches_reference(&scene, &positions, &normals);
        for (p, n) in positions.iter().zip(&normals) {
            assert_kernel_matches_reference(&scene, &[*p], &[*n]);
        }
    }
}

/// A positional light far away (1e30 along +z, within MAX_COORDINATE) with
/// k = (1, 0, 0) has att = 1/(1 + 0·d + 0·d²) = 1 and VP = +z: it is GL_LIGHT0.
/// Overhead on GL's default material: 0.04 + 0.8 = 0.84 (see golden). With
/// k = (1, 1e-30, 0), att = 1/(1 + 1e-30·1e30) = 1/2: 0.04 + 0.4.
/// In f32, d² = 1e60 overflows: k2·d² must still be 0 when k2 = 0, not
/// 0·∞ = NaN.
#[test]
fn kernel_far_positional_light() {
    for k in [[1.0, 0.0, 0.0], [1.0, 1e-30, 0.0]] {
        let far = Light {
            position: LightPosition::Positional(DVec3::new(0.0, 0.0, 1e30)),
            attenuation: k,
            ..Light::default()
        };
        let scene = eye_space(LightModel::default(), Material::default(), vec![far]);
        let positions = [DVec3::ZERO];
        let normals = [DVec3::Z];
        let att = 1.0 / (k[0] + k[1] * 1e30);
        let expected = 0.04 + att * 0.8;
        for (tier, bound) in TIERS {
            assert_close!(
                scene.kernel_colors(tier, &positions, &normals).front[0],
                DVec4::new(expected, expected, expected, 1.0),
                tol = bound,
                "{tier:?}, k = {k:?}"
            );
        }
        assert_kernel_matches_reference(&scene, &positions, &normals);
    }
}

/// A light a hair from the vertex (distances down to 1e-35, which f32 holds
/// as normal numbers once recentred on the vertex) still has a direction:
/// VP = (0,1,1)/√2, so n·VP = 1 for n = (0,1,1)/√2 and the colour is GL's
/// default 0.04 + 0.8·1 = 0.84 (k = (1,0,0): no attenuation).
#[test]
fn kernel_light_a_hair_from_the_vertex() {
    let n = unit(0.0, 1.0, 1.0);
    for distance in [1e-10, 1e-20, 1e-30, 1e-33, 1e-35] {
        let light = Light {
            position: LightPosition::Positional(n * distance),
            ..Light::default()
        };
        let scene = eye_space(LightModel::default(), Material::default(), vec![light]);
        let expected = DVec4::new(0.84, 0.84, 0.84, 1.0);
        assert_close!(
            scene.color(Side::Front, DVec3::ZERO, n),
            expected,
            tol = 1e-12,
            "reference, distance {distance:e}"
        );
        for (tier, bound) in TIERS {
            assert_close!(
                scene.kernel_colors(tier, &[DVec3::ZERO], &[n]).front[0],
                expected,
                tol = bound,
                "{tier:?}, distance {distance:e}"
            );
        }
    }
}

/// The documented bound is absolute, so it must hold even where large
/// terms cancel into [0, 1]. Two lights whose terms are about ±1000 and sum
/// to exactly 0.5 by hand (light colours may be negative; attenuation and
/// un-normalised normals may make terms large):
///
/// 1. Attenuation. Vertex at the origin, n = +z, k = (0, 0, 1), diffuse only
///    (d_cm = 1):
///    - light A at (0, 0, 0.03): d = 0.03, att = 1/0.0009, n·VP = 1,
///      d_cli = 1: term 1/0.0009 ≈ 1111.1;
///    - light B at (0, 0.03, 0.04): d = 0.05, att = 1/0.0025 = 400,
///      VP = (0, 0.6, 0.8), n·VP = 0.8, d_cli = −c: term −320c;
///    - c = (1/0.0009 − 0.5)/320 makes the sum 0.5.
/// 2. A raw normal of length 2 (normalisation off), specular only
///    (s_cm = 1, shininess 10, infinite viewer +z):
///    - light A towards +z: ĥ = +z, n·ĥ = 2, term 2^10 = 1024;
///    - light B towards VP = (sin θ, 0, cos θ): ĥ bisects θ, n·ĥ = 2cos(θ/2)
///      with cos²(θ/2) = (1 + cos θ)/2; s_cli = −c with
///      c = (1024 − 0.5)/(2cos(θ/2))^10.
///
/// f32 holds 1024 to 1.2e-4, so an f32 sum of these terms cannot meet 1e-5.
#[test]
fn kernel_warns_when_large_terms_cancel() {
    let half = DVec4::new(0.5, 0.5, 0.5, 1.0);

    let c = (1.0 / 0.0009 - 0.5) / 320.0;
    let near = |position: DVec3, diffuse: f64| Light {
        diffuse: grey(diffuse),
        attenuation: [0.0, 0.0, 1.0],
        ..black_light(LightPosition::Positional(position))
    };
    let attenuated = eye_space(
        dark_model(),
        Material {
            diffuse: grey(1.0),
            ..black_material()
        },
        vec![
            near(DVec3::new(0.0, 0.0, 0.03), 1.0),
            near(DVec3::new(0.0, 0.03, 0.04), -c),
        ],
    );

    let b = unit(0.1, 0.0, 1.0);
    let cos_half_sq = (1.0 + b.z) / 2.0;
    let c = (1024.0 - 0.5) / (4.0 * cos_half_sq).powi(5); // (2cos(θ/2))^10
    let specular = |towards_light: DVec3, color: f64| Light {
        specular: grey(color),
        ..black_light(LightPosition::Directional(towards_light))
    };
    let long_normal = eye_space(
        LightModel {
            normalize_normals: false,
            ..dark_model()
        },
        Material {
            specular: grey(1.0),
            shininess: 10.0,
            ..black_material()
        },
        vec![specular(DVec3::Z, 1.0), specular(b, -c)],
    );

    for (name, scene, n) in [
        ("attenuation", attenuated, DVec3::Z),
        (
            "raw normal of length 2",
            long_normal,
            DVec3::new(0.0, 0.0, 2.0),
        ),
    ] {
        // The hand computation, checked against the reference first.
        assert_close!(
            scene.color(Side::Front, DVec3::ZERO, n),
            half,
            tol = 1e-9,
            "reference, {name}"
        );
        // f32 holds the ±1024 terms to 1.2e-4, so the absolute bound cannot
        // hold: the service must say so, and the error must stay within the
        // bound scaled by the largest term (the promise of the warning).
        let largest = scene
            .evaluate(Side::Front, DVec3::ZERO, n)
            .lights
            .iter()
            .flat_map(|l| [l.ambient, l.diffuse, l.specular])
            .map(|t| t.abs().max_element())
            .fold(1.0, f64::max);
        for (tier, bound) in TIERS {
            assert_close!(
                scene.kernel_colors(tier, &[DVec3::ZERO], &[n]).front[0],
                half,
                tol = bound * largest,
                "{tier:?} tier, {name}"
            );
        }
        assert!(warns_precision_bound(&scene, DVec3::ZERO, n), "{name}");
    }
}

/// Whether `/v1/shade` in each f32 precision warns that its bound cannot
/// hold for this scene.
fn warns_precision_bound(scene: &Scene, v: DVec3, n: DVec3) -> bool {
    [Precision::Accurate, Precision::Fast]
        .into_iter()
        .all(|precision| {
            let request = ShadeScene {
                lights: scene.lights.clone(),
                material: scene.material,
                positions: vec![v],
                normals: vec![n],
                precision,
                terms: TermsDetail::None,
                zero_normals: 0,
            };
            glint::shade::shade(&request)
                .warnings
                .iter()
                .any(|w| w.code == "precision_bound")
        })
}

/// With normalisation off, a raw normal longer than 1 makes the specular
/// base exceed 1, and its f32 rounding, raised to a high shininess (111.5,
/// above the 64 past which glint warns that f32 cannot hold its bound),
/// moves a term near 1 by more than 1e-5: the service says so. One light, Phong, local viewer at
/// the origin, back side, |n| ≈ 1.6 (the case proptest found, shrunk).
/// The expected colour is the reference's; the reference's own terms are
/// checked by the golden and edge-case tests.
#[test]
fn kernel_warns_for_a_raw_normal_longer_than_1_at_high_shininess() {
    let material = Material {
        specular: DVec4::new(0.0, 0.6711176077165677, 0.0, 0.0),
        shininess: 111.54326610768719,
        ..black_material()
    };
    let scene = Scene {
        lights: light_set(
            LightModel {
                ambient: DVec4::ZERO,
                local_viewer: true,
                two_side: true,
                specular_model: SpecularModel::Phong,
                normalize_normals: false,
                ..LightModel::default()
            },
            vec![Light {
                position: LightPosition::Positional(DVec3::new(
                    -0.6891845735386916,
                    -3.3061094178156782,
                    -6.588975344575175,
                )),
                specular: DVec4::new(0.0, 0.9879246091358748, 0.0, 0.0),
                attenuation: [0.0, 0.9748154688853026, 0.3088304856156343],
                ..black_light(LightPosition::Directional(DVec3::Z))
            }],
            Viewer::Local(DVec3::ZERO),
        ),
        material: SurfaceMaterial {
            front: black_material(),
            back: material,
        },
    };
    let v = DVec3::new(-6.341349869678446, 7.40689428462886, -0.02374509830321904);
    let n = DVec3::new(-1.098035429039031, 0.8438435613529631, -0.8546210796841205);
    let b = scene.evaluate(Side::Back, v, n);
    // The premise: a single term, below 1, so the bound is not scaled away.
    assert!(b.unclamped().max_element() < 1.0, "{b:?}");
    assert!(warns_precision_bound(&scene, v, n));
}

/// The output's shape: one colour per vertex, back colours only with
/// two-sided lighting, and an empty batch gives empty output.
#[test]
fn kernel_output_shape() {
    let one_sided = eye_space(
        LightModel::default(),
        Material::default(),
        vec![Light::default()],
    );
    let two_sided = eye_space(
        LightModel {
            two_side: true,
            ..LightModel::default()
        },
        Material::default(),
        vec![Light::default()],
    );
    let (positions, normals) = grid(0.0);
    for (tier, _) in TIERS {
        let colors = one_sided.kernel_colors(tier, &positions, &normals);
        assert_eq!(colors.front.len(), positions.len());
        assert!(colors.back.is_none());

        let colors = two_sided.kernel_colors(tier, &positions, &normals);
        assert_eq!(colors.back.as_ref().map(Vec::len), Some(positions.len()));

        let empty = two_sided.kernel_colors(tier, &[], &[]);
        assert!(empty.front.is_empty());
        assert_eq!(empty.back, Some(vec![]));
    }
}

/// Batches of every length around the evaluator's blocks and tasks (blocks
/// of 64 vertices, tasks of 64 blocks) come back complete and in order:
/// vertex i is lit like the reference's vertex i, on both sides. Normals
/// around a half ring, in a scrambled order, under a light at 45° give
/// each vertex a colour far from its neighbours'. Batches of more than one
/// task prefetch blocks ahead, up to the end of each task.
#[test]
fn kernel_keeps_vertex_order_across_blocks_and_tasks() {
    for n in [1, 63, 64, 65, 127, 4095, 4096, 4097, 10_000, 300_001] {
        let normals: Vec<DVec3> = (0..n)
            .map(|i| {
                // 7919 is prime and divides none of the lengths: a permutation.
                let a = (i as u64 * 7919 % n as u64) as f64 / n as f64 * std::f64::consts::PI;
                DVec3::new(a.cos(), 0.0, a.sin())
            })
            .collect();
        let positions: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(i as f64 * 1e-3, 0.0, 0.0))
            .collect();
        let light = Light {
            position: LightPosition::Directional(DVec3::new(R2, 0.0, R2)),
            ..Light::default()
        };
        let scene = eye_space(
            LightModel {
                two_side: true,
                ..LightModel::default()
            },
            // Channels of their own, so that a swap of two shows.
            Material {
                diffuse: rgb(0.8, 0.5, 0.2),
                ..Material::default()
            },
            vec![light],
        );
        assert_kernel_matches_reference(&scene, &positions, &normals);
    }
}

/// `Kernel::new` takes the positions only to choose its centre: shading a
/// batch with a kernel built for another batch nearby gives the same colours.
#[test]
fn kernel_centre_only_affects_rounding() {
    let scene = eye_space(LightModel::default(), shiny(), assorted_lights());
    let (positions, normals) = grid(0.0);
    for (tier, bound) in TIERS {
        let a = scene.kernel_colors(tier, &positions, &normals);
        let elsewhere = Kernel::new(&scene.lights, &[DVec3::new(5.0, 5.0, 5.0)]);
        let products = elsewhere.products(&scene.material);
        let b = elsewhere.light(tier, &products, &elsewhere.prepare(&positions, &normals));
        for (i, (x, y)) in a.front.iter().zip(&b.front).enumerate() {
            assert_close!(*x, *y, tol = bound, "{tier:?}, vertex {i}");
        }
    }
}

/// `light_into` reuses its buffers: after a larger two-sided batch, a
/// smaller one-sided one gives exactly the colours of a fresh call, and no
/// back colours.
#[test]
fn light_into_reuses_buffers_without_leaking_old_colours() {
    let (positions, normals) = grid(0.0);
    let two_sided = eye_space(
        LightModel {
            two_side: true,
            ..LightModel::default()
        },
        shiny(),
        assorted_lights(),
    );
    let one_sided = eye_space(LightModel::default(), shiny(), assorted_lights());
    let few = positions.len() / 3;
    for (tier, _) in TIERS {
        let mut out = Colors::default();
        let kernel = Kernel::new(&two_sided.lights, &positions);
        let products = kernel.products(&two_sided.material);
        let vertices = kernel.prepare(&positions, &normals);
        kernel.light_into(tier, &products, &vertices, &mut out);
        assert_eq!(out.back.as_ref().map(Vec::len), Some(positions.len()));
        let kernel = Kernel::new(&one_sided.lights, &positions[..few]);
        let products = kernel.products(&one_sided.material);
        let vertices = kernel.prepare(&positions[..few], &normals[..few]);
        kernel.light_into(tier, &products, &vertices, &mut out);
        assert_eq!(out, kernel.light(tier, &products, &vertices), "{tier:?}");
        assert_eq!(out.front.len(), few);
    }
}

/// The state key names the features that shape the vertex loop (each
/// checked on its own, so that new fields do not break the test).
#[test]
fn state_key_follows_the_scene() {
    let key = |scene: &Scene| state_key(scene, &[]);
    let matte = Material {
        specular: BLACK_SPECULAR,
        ..Material::default()
    };
    let base = eye_space(LightModel::default(), matte, vec![Light::default()]);
    let k = key(&base);
    assert!(!k.local_viewer && !k.specular && !k.phong, "{k:?}");

    let mut shiny_back = base.clone();
    shiny_back.lights.model.two_side = true;
    shiny_back.material.back.specular = grey(0.5);
    assert!(key(&shiny_back).specular, "a specular back side counts");

    let mut local_phong = base.clone();
    local_phong.lights.viewer = Viewer::Local(DVec3::ZERO);
    local_phong.lights.model.specular_model = SpecularModel::Phong;
    let k = key(&local_phong);
    assert!(k.local_viewer && !k.specular && k.phong, "{k:?}");
}

/// The state key of `scene`'s material under its lights, prepared for
/// `positions`.
fn state_key(scene: &Scene, positions: &[DVec3]) -> StateKey {
    let kernel = Kernel::new(&scene.lights, positions);
    kernel.state_key(&kernel.products(&scene.material))
}

const BLACK_SPECULAR: DVec4 = DVec4::new(0.0, 0.0, 0.0, 1.0);

/// Every block function (local viewer × specular × Phong) and every light
/// loop (directional; positional with and without attenuation, with and
/// without a cone) against the reference, on both tiers.
#[test]
fn kernel_matches_reference_for_every_state_key() {
    let (positions, normals) = grid(-0.5);
    let mut lights = assorted_lights();
    // Positional with k = (1, 0, 0), with and without a cone.
    lights.push(Light {
        position: LightPosition::Positional(DVec3::new(-1.0, -1.0, 2.0)),
        ..Light::default()
    });
    lights.push(Light {
        position: LightPosition::Positional(DVec3::new(1.0, -1.0, 3.0)),
        diffuse: grey(0.3),
        spot: Spot {
            direction: unit(0.0, 0.2, -1.0),
            exponent: 5.0,
            cutoff: 50.0,
        },
        ..Light::default()
    });
    for local_viewer in [false, true] {
        for specular in [false, true] {
            for specular_model in [SpecularModel::BlinnPhong, SpecularModel::Phong] {
                let model = LightModel {
                    local_viewer,
                    specular_model,
                    ..LightModel::default()
                };
                let material = if specular {
                    shiny()
                } else {
                    Material {
                        specular: BLACK_SPECULAR,
                        ..shiny()
                    }
                };
                let mut scene = eye_space(model, material, lights.clone());
                if !specular {
                    // No specular product at all: s_cli may be anything.
                    assert!(!state_key(&scene, &positions).specular);
                }
                scene.lights.model.two_side = local_viewer;
                assert_kernel_matches_reference(&scene, &positions, &normals);
            }
        }
    }
}

/// GL's default material and light model under one spotlight at the origin
/// shining along −z.
fn spot_along_negative_z(cutoff: f64, exponent: f64) -> Scene {
    let light = Light {
        position: LightPosition::Positional(DVec3::ZERO),
        spot: Spot {
            direction: DVec3::NEG_Z,
            exponent,
            cutoff,
        },
        ..Light::default()
    };
    eye_space(LightModel::default(), Material::default(), vec![light])
}

/// Near the edge of a wide cone: points almost perpendicular to the axis of
/// a 90° cone (exponent 0, so spot = 1 inside) and points a hair inside and
/// outside a 60° and an 80° cone. The kernels test wide cones on cos², which
/// keeps these decisions where the reference makes them.
#[test]
fn wide_cone_edges_follow_the_reference() {
    for (cutoff, exponent) in [(90.0, 0.0), (80.0, 2.0), (60.0, 0.5)] {
        let scene = spot_along_negative_z(cutoff, exponent);
        let edge = f64::to_radians(cutoff);
        let mut positions = Vec::new();
        for offset in [-1e-3, -1e-5, 1e-5, 1e-3] {
            let angle = edge + offset;
            if angle < std::f64::consts::FRAC_PI_2 {
                positions.push(DVec3::new(angle.sin(), 0.0, -angle.cos()) * 3.0);
            }
        }
        // Facing the light, so that the spot decides the diffuse term.
        let normals: Vec<DVec3> = positions.iter().map(|p| -p.normalize()).collect();
        assert_kernel_matches_reference(&scene, &positions, &normals);
    }
}

/// The fast tier tests cones of 30° and more on `cos²` alone, and a block
/// with a `cos²` near the cutoff's again, exactly. Vertices within 1e-6
/// radians of the edge, their coordinates on a grid of 2^−20 so that the
/// kernel's f32 inputs are the reference's (recentred on the middle of their
/// box, on the grid too): every decision is the reference's, even a hair
/// from the edge, where the f32 error of `cos²` alone could flip it.
#[test]
fn fast_cone_edges_on_exact_inputs_follow_the_reference() {
    let grid = |x: f64| (x * 2f64.powi(20)).round() / 2f64.powi(20);
    for (cutoff, exponent) in [(30.0, 8.0), (40.0, 8.0), (60.0, 128.0), (89.0, 2.0)] {
        let scene = spot_along_negative_z(cutoff, exponent);
        let mut positions = Vec::new();
        for i in 0..2000 {
            let angle = f64::to_radians(cutoff) + (i % 41) as f64 * 5e-8 - 1e-6;
            let azimuth = i as f64 * 0.618;
            let p = DVec3::new(
                angle.sin() * azimuth.cos(),
                angle.sin() * azimuth.sin(),
                -angle.cos(),
            ) * 3.0;
            positions.push(p.map(grid));
        }
        // Facing the light, so that the spot decides the diffuse term.
        let normals: Vec<DVec3> = positions.iter().map(|p| -p.normalize()).collect();
        let colors = scene.kernel_colors(Tier::Fast, &positions, &normals);
        for (i, (p, n)) in positions.iter().zip(&normals).enumerate() {
            let expected = scene.color(Side::Front, *p, *n);
            assert!(
                (colors.front[i].as_dvec4() - expected).abs().max_element() <= FAST_TOL,
                "{cutoff}°, vertex {i} at {p}: {} against {expected}",
                colors.front[i]
            );
        }
    }
}

/// A spotlight lights a few lone vertices among many it misses, with runs
/// of misses longer than a block: the kernels skip a light for a block that
/// lies wholly outside its cone, and must not skip the vertices of a block
/// that has one inside, wherever it is in the block.
#[test]
fn a_cone_that_misses_most_vertices_still_lights_the_ones_it_reaches() {
    // A batch of whole blocks, and one whose last block is partial, lit on
    // both sides.
    for (cutoff, count, two_side) in [(20.0, 256, false), (40.0, 256, false), (40.0, 250, true)] {
        let mut scene = spot_along_negative_z(cutoff, 8.0);
        scene.lights.model.two_side = two_side;
        let lit = [0, 63, 64, 127, 200];
        let positions: Vec<DVec3> = (0..count)
            .map(|i| {
                if lit.contains(&i) {
                    DVec3::new(0.001 * i as f64, 0.0, -3.0)
                } else {
                    DVec3::new(3.0, 0.01 * i as f64, -1.0)
                }
            })
            .collect();
        let normals: Vec<DVec3> = positions.iter().map(|p| -p.normalize()).collect();
        assert_kernel_matches_reference(&scene, &positions, &normals);
        // The lone vertices are lit, the others have the global ambient alone.
        let colors = scene.kernel_colors(Tier::Fast, &positions, &normals);
        for (i, c) in colors.front.iter().enumerate() {
            assert_eq!(lit.contains(&i), c.x > 0.5, "vertex {i}: {c}");
        }
    }
}

/// GL's default material under two lights from +z: L0 with a_cl = 0.5 and
/// d_cl = 1, L1 with d_cl = 0.5. The global ambient gives 0.2·0.2 = 0.04,
/// L0's ambient 0.2·0.5 = 0.1, L0's diffuse 0.8, L1's diffuse 0.8·0.5 = 0.4.
fn two_lights_from_z() -> Scene {
    let lights = vec![
        Light {
            ambient: grey(0.5),
            ..Light::default()
        },
        Light {
            diffuse: grey(0.5),
            ..Light::default()
        },
    ];
    eye_space(LightModel::default(), Material::default(), lights)
}

/// Visibility masks: a light that does not reach a vertex (the renderer's
/// shadow) adds only its ambient term, and bit `i` is light `i`; the scene
/// of [`two_lights_from_z`].
#[test]
fn a_light_that_does_not_reach_a_vertex_adds_only_its_ambient_term() {
    let scene = two_lights_from_z();
    let cases = [
        (DVec3::Z, 0b11, 1.0), // 1.34, clamped
        (DVec3::Z, 0b01, 0.94),
        (DVec3::Z, 0b10, 0.54),
        (DVec3::Z, 0b00, 0.14),
        (DVec3::NEG_Z, 0b11, 0.14), // facing away: the masks do not matter
    ];
    let positions = vec![DVec3::ZERO; cases.len()];
    let normals: Vec<DVec3> = cases.iter().map(|c| c.0).collect();
    let kernel = Kernel::new(&scene.lights, &positions);
    let products = kernel.products(&scene.material);
    let mut vertices = kernel.prepare(&positions, &normals);
    vertices.set_visibility(cases.iter().map(|c| c.1).collect());
    for (tier, bound) in TIERS {
        let colors = kernel.light(tier, &products, &vertices);
        for (&(n, mask, grey), got) in cases.iter().zip(&colors.front) {
            let want = DVec4::new(grey, grey, grey, 1.0);
            assert_close!(
                *got,
                want,
                tol = bound,
                "{tier:?}, normal {n}, mask {mask:02b}"
            );
        }
    }
}

/// A batch without masks, lit on the thread that has just lit one whose
/// masks stopped every light, is lit by all its lights: the kernel keeps
/// its working block from one batch to the next, never its masks. The
/// scene of [`two_lights_from_z`]: with both lights 1.34, clamped to 1.
#[test]
fn the_masks_of_one_batch_do_not_reach_the_next() {
    let scene = two_lights_from_z();
    let positions = vec![DVec3::ZERO; 3];
    let normals = vec![DVec3::Z; 3];
    let kernel = Kernel::new(&scene.lights, &positions);
    let products = kernel.products(&scene.material);
    let mut shadowed = kernel.prepare(&positions, &normals);
    shadowed.set_visibility(vec![0; 3]);
    let open = kernel.prepare(&positions, &normals);
    for (tier, bound) in TIERS {
        let dark = kernel.light(tier, &products, &shadowed);
        let lit = kernel.light(tier, &products, &open);
        for (d, l) in dark.front.iter().zip(&lit.front) {
            assert_close!(
                *d,
                DVec4::new(0.14, 0.14, 0.14, 1.0),
                tol = bound,
                "{tier:?}"
            );
            assert_close!(*l, DVec4::ONE, tol = bound, "{tier:?}");
        }
    }
}

/// The back side negates the normal and uses the back material: the light
/// below lights the back (d_bm = (0, 0, 1), alpha 0.5), not the front.
#[test]
fn the_back_side_is_lit_with_the_back_material() {
    let scene = Scene {
        lights: light_set(
            LightModel {
                two_side: true,
                ..dark_model()
            },
            vec![Light {
                position: LightPosition::Directional(DVec3::NEG_Z),
                ..Light::default()
            }],
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
    for (tier, bound) in TIERS {
        let colors = scene.kernel_colors(tier, &[DVec3::ZERO], &[DVec3::Z]);
        let back = colors.back.expect("two-sided");
        assert_close!(back[0], DVec4::new(0.0, 0.0, 1.0, 0.5), tol = bound);
        assert_close!(colors.front[0], DVec4::new(0.0, 0.0, 0.0, 1.0), tol = bound);
    }
}

/// A 0° cone lights exactly the points on its axis (spot = 1 there) and
/// nothing else; the decision is exact in the reference for an axis-aligned
/// cone, and must be in the kernel: on the axis, P_pli V = ŝ exactly.
/// Light at the origin pointing down; vertices on the −z axis at assorted
/// distances, facing the light: a_cm·a_cli + d_cm·d_cli = 0.2·0.5 + 0.8·0.5
/// = 0.5, plus the global ambient 0.04.
#[test]
fn kernel_cutoff_0_lights_the_axis() {
    let light = Light {
        position: LightPosition::Positional(DVec3::ZERO),
        ambient: grey(0.5),
        diffuse: grey(0.5),
        specular: BLACK_SPECULAR,
        spot: Spot {
            direction: DVec3::NEG_Z,
            exponent: 3.0,
            cutoff: 0.0,
        },
        ..Light::default()
    };
    let scene = eye_space(LightModel::default(), Material::default(), vec![light]);
    let expected = DVec4::new(0.54, 0.54, 0.54, 1.0);
    // One batch along the axis, and single-vertex batches very near and
    // very far (in one batch with the others, f32 could not tell a vertex
    // 1e-3 from the light from the light itself).
    let along: Vec<DVec3> = (1..=40)
        .map(|i| DVec3::new(0.0, 0.0, -(i as f64) * 0.37))
        .collect();
    let batches = [
        along,
        vec![DVec3::new(0.0, 0.0, -1e-3)],
        vec![DVec3::new(0.0, 0.0, -1e6)],
    ];
    for positions in &batches {
        let normals = vec![DVec3::Z; positions.len()];
        let kernel = Kernel::new(&scene.lights, positions);
        let products = kernel.products(&scene.material);
        for (i, p) in positions.iter().enumerate() {
            assert_close!(
                scene.color(Side::Front, *p, DVec3::Z),
                expected,
                tol = 1e-12,
                "reference, vertex {i} at {p:?}"
            );
        }
        for (tier, bound) in TIERS {
            let colors = kernel.light(tier, &products, &kernel.prepare(positions, &normals));
            for (i, (p, c)) in positions.iter().zip(&colors.front).enumerate() {
                assert_close!(*c, expected, tol = bound, "{tier:?}, vertex {i} at {p:?}");
            }
        }
    }
    // A hair off the axis: dark.
    let off = [DVec3::new(1e-3, 0.0, -1.0)];
    for (tier, bound) in TIERS {
        assert_close!(
            scene.kernel_colors(tier, &off, &[DVec3::Z]).front[0],
            DVec4::new(0.04, 0.04, 0.04, 1.0),
            tol = bound,
            "{tier:?}, off the axis"
        );
    }
}
