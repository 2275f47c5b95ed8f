//! The precision tiers against the reference: each stays within its
//! documented bound on random scenes and at the extremes, never yields NaN
//! or infinity, and says so (a warning) where its bound cannot hold.

use glam::{DVec3, DVec4, Vec4};
use glint::response::MAX_BOUNDED_RAW_SHININESS;
use glint::scene::{ShadeScene, TermsDetail};
use glint_lighting::kernel::{Kernel, Tier};
use glint_lighting::{
    Light, LightModel, LightPosition, LightSet, Material, Precision, Side, Spot, SurfaceMaterial,
    Viewer,
};
use proptest::prelude::*;

use crate::lighting::support::{Scene, light_set, model_of, with_lights};

/// The largest difference, over every channel of every vertex and side,
/// between a tier's colours and the reference's; panics on a non-finite one.
fn worst_error(scene: &Scene, tier: Tier, positions: &[DVec3], normals: &[DVec3]) -> f64 {
    let kernel = Kernel::new(&scene.lights, positions);
    let products = kernel.products(&scene.material);
    let colors = kernel.light(tier, &products, &kernel.prepare(positions, normals));
    let mut worst: f64 = 0.0;
    let mut compare = |side: Side, got: &[Vec4]| {
        for ((p, n), c) in positions.iter().zip(normals).zip(got) {
            assert!(c.is_finite(), "{tier:?} gave {c} at {p} {n}");
            let expected = scene.color(side, *p, *n);
            worst = worst.max((c.as_dvec4() - expected).abs().max_element());
        }
    };
    compare(Side::Front, &colors.front);
    if let Some(back) = &colors.back {
        compare(Side::Back, back);
    }
    worst
}

fn bound(tier: Tier) -> f64 {
    match tier {
        Tier::Accurate => Precision::Accurate.max_abs_error(),
        Tier::Fast => Precision::Fast.max_abs_error(),
    }
}

fn assert_within_bounds(scene: &Scene, positions: &[DVec3], normals: &[DVec3]) {
    for tier in [Tier::Accurate, Tier::Fast] {
        let worst = worst_error(scene, tier, positions, normals);
        assert!(
            worst <= bound(tier),
            "{tier:?}: error {worst:e} over its bound {:e}",
            bound(tier)
        );
    }
}

fn color() -> impl Strategy<Value = DVec4> {
    prop::array::uniform4(0.0..1.0f64).prop_map(DVec4::from_array)
}

fn unit() -> impl Strategy<Value = DVec3> {
    prop::array::uniform3(-1.0..1.0f64)
        .prop_filter("not tiny", |v| DVec3::from_array(*v).length() > 0.1)
        .prop_map(|v| DVec3::from_array(v).normalize())
}

fn material() -> impl Strategy<Value = Material> {
    (color(), color(), color(), color(), 0.0..128.0f64).prop_map(
        |(ambient, diffuse, specular, emission, shininess)| Material {
            ambient,
            diffuse,
            specular,
            emission: emission * 0.2,
            shininess,
        },
    )
}

fn light() -> impl Strategy<Value = Light> {
    let position = prop_oneof![
        unit().prop_map(LightPosition::Directional),
        prop::array::uniform3(-10.0..10.0f64)
            .prop_map(|p| LightPosition::Positional(DVec3::from_array(p))),
    ];
    let spot = prop_oneof![
        Just(Spot::default()),
        (unit(), 0.0..128.0f64, 0.0..90.0f64).prop_map(|(direction, exponent, cutoff)| Spot {
            direction,
            exponent,
            cutoff,
        }),
    ];
    (
        position,
        color(),
        color(),
        color(),
        prop::array::uniform3(0.0..1.0f64),
        spot,
    )
        .prop_map(|(position, ambient, diffuse, specular, k, spot)| Light {
            position,
            ambient: ambient * 0.2,
            diffuse,
            specular,
            attenuation: [k[0] + 0.5, k[1], k[2] * 0.1],
            spot,
        })
}

fn scene() -> impl Strategy<Value = Scene> {
    (
        material(),
        material(),
        prop::collection::vec(light(), 0..8),
        any::<[bool; 6]>(),
    )
        .prop_map(|(front, back, lights, flags)| {
            let model = model_of(LightModel::default().ambient, flags);
            Scene {
                lights: light_set(
                    model,
                    lights,
                    LightSet::eye_space_viewer(model.local_viewer),
                ),
                material: SurfaceMaterial { front, back },
            }
        })
}

fn vertices() -> impl Strategy<Value = Vec<(DVec3, DVec3)>> {
    prop::collection::vec(
        (prop::array::uniform3(-5.0..5.0f64), unit()).prop_map(|(p, n)| (DVec3::from_array(p), n)),
        1..200,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn every_tier_stays_within_its_bound_on_random_scenes(
        scene in scene(),
        vertices in vertices(),
    ) {
        let (positions, normals): (Vec<_>, Vec<_>) = vertices.into_iter().unzip();
        let shininess = scene.material.front.shininess.max(scene.material.back.shininess);
        if !scene.lights.model.normalize_normals && shininess > MAX_BOUNDED_RAW_SHININESS {
            // Outside the promise: the response warns (see the test below).
            for tier in [Tier::Accurate, Tier::Fast] {
                worst_error(&scene, tier, &positions, &normals);
            }
        } else {
            assert_within_bounds(&scene, &positions, &normals);
        }
    }
}

/// `scene` with every shininess and spot exponent rounded to an even
/// whole number (or, for odd `choice`, to an odd one): the powers the
/// kernels take by multiplication, and their neighbours that they do not.
fn whole_exponents(mut scene: Scene, choice: u8) -> Scene {
    let whole = |x: f64| {
        let even = 2.0 * (x / 2.0).round();
        if choice % 2 == 1 { even + 1.0 } else { even }
    };
    scene.material.front.shininess = whole(scene.material.front.shininess);
    scene.material.back.shininess = whole(scene.material.back.shininess);
    for light in scene.lights.lights_mut() {
        light.spot.exponent = whole(light.spot.exponent);
    }
    scene
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn whole_shininess_and_spot_exponents_stay_within_the_bounds(
        scene in scene(),
        choice in any::<u8>(),
        vertices in vertices(),
    ) {
        let scene = whole_exponents(scene, choice);
        let (positions, normals): (Vec<_>, Vec<_>) = vertices.into_iter().unzip();
        let shininess = scene.material.front.shininess.max(scene.material.back.shininess);
        if scene.lights.model.normalize_normals || shininess <= MAX_BOUNDED_RAW_SHININESS {
            assert_within_bounds(&scene, &positions, &normals);
        }
    }
}

/// Whole powers (taken by multiplication up to a shininess of 64 in the
/// accurate tier and 2048 in the fast one) near and far from the
/// highlight, from a light at infinity (one `ĥ`) and from a light at a
/// point seen by a local viewer (an `ĥ` per vertex), at the largest whole
/// powers of each tier and just past them.
#[test]
fn whole_powers_near_highlights() {
    let point = Light {
        position: LightPosition::Positional(DVec3::new(0.0, 0.0, 4.0)),
        ..Light::default()
    };
    for shininess in [
        2.0, 8.0, 32.0, 62.0, 64.0, 66.0, 128.0, 2046.0, 2048.0, 2050.0,
    ] {
        for spread in [0.01, 0.1, 1.5] {
            let (p, n) = fan(2000, spread);
            assert_within_bounds(&single(shiny(shininess), Light::default()), &p, &n);
            let mut local = single(shiny(shininess), point);
            local.lights.model.local_viewer = true;
            local.lights.viewer = Viewer::Local(DVec3::new(0.5, 0.0, 3.0));
            let p: Vec<DVec3> = n.iter().map(|n| DVec3::new(n.x, 0.0, 0.0)).collect();
            assert_within_bounds(&local, &p, &n);
        }
    }
}

/// One material, one light, one vertex at the origin facing +z.
fn single(material: Material, light: Light) -> Scene {
    Scene {
        lights: light_set(
            LightModel::default(),
            vec![light],
            Viewer::Infinite(DVec3::Z),
        ),
        material: SurfaceMaterial::both_sides(material),
    }
}

fn shiny(shininess: f64) -> Material {
    Material {
        specular: DVec4::ONE,
        shininess,
        ..Material::default()
    }
}

/// Normals fanning from +z towards +x: n·ĥ sweeps from 1 down.
fn fan(count: usize, max_angle: f64) -> (Vec<DVec3>, Vec<DVec3>) {
    (0..count)
        .map(|i| {
            let a = max_angle * i as f64 / count as f64;
            (DVec3::ZERO, DVec3::new(a.sin(), 0.0, a.cos()))
        })
        .unzip()
}

#[test]
fn shininess_at_the_ends_of_its_range() {
    for shininess in [0.0, 1e-6, 1.0, 128.0] {
        let (p, n) = fan(2000, 1.5);
        assert_within_bounds(&single(shiny(shininess), Light::default()), &p, &n);
    }
}

#[test]
fn a_shininess_of_1e4_stays_within_the_bounds_with_unit_normals() {
    for spread in [0.02, 0.2, 1.5] {
        let (p, n) = fan(2000, spread);
        assert_within_bounds(&single(shiny(1e4), Light::default()), &p, &n);
    }
}

#[test]
fn a_shininess_of_1e4_on_raw_normals_is_finite_and_warned_about() {
    let (positions, normals) = fan(2000, 0.2);
    let mut scene = single(shiny(1e4), Light::default());
    scene.lights.model.normalize_normals = false;
    for tier in [Tier::Accurate, Tier::Fast] {
        // Finite whatever the error; the bound is the warning's business.
        worst_error(&scene, tier, &positions, &normals);
    }
    let request = |precision| ShadeScene {
        lights: scene.lights.clone(),
        material: scene.material,
        positions: positions.clone(),
        normals: normals.clone(),
        precision,
        terms: TermsDetail::None,
        zero_normals: 0,
    };
    let warned = |precision| {
        glint::shade::shade(&request(precision))
            .warnings
            .iter()
            .any(|w| w.code == "precision_bound")
    };
    assert!(warned(Precision::Accurate) && warned(Precision::Fast));
    assert!(!warned(Precision::Reference), "the reference is exact");
}

#[test]
fn spot_exponents_near_the_axis() {
    for exponent in [0.0, 1.0, 2.0, 8.0, 64.0, 127.0, 128.0, 1e4] {
        let light = Light {
            position: LightPosition::Positional(DVec3::new(0.0, 0.0, 5.0)),
            spot: Spot {
                direction: DVec3::NEG_Z,
                exponent,
                cutoff: 30.0,
            },
            ..Light::default()
        };
        // Vertices just off the axis: cos of the angle within 1e-6 of 1.
        let positions: Vec<DVec3> = (0..500)
            .map(|i| DVec3::new(i as f64 * 1e-5, 0.0, 0.0))
            .collect();
        let normals = vec![DVec3::Z; positions.len()];
        assert_within_bounds(&single(Material::default(), light), &positions, &normals);
    }
}

#[test]
fn grazing_light() {
    // n·VP exactly 0, and just above it.
    let normals: Vec<DVec3> = [0.0, 1e-7, 1e-6, 1e-3]
        .iter()
        .map(|&t| DVec3::new(-t, 1.0, 0.0).normalize())
        .collect();
    let positions = vec![DVec3::ZERO; normals.len()];
    let light = Light {
        position: LightPosition::Directional(DVec3::X),
        ..Light::default()
    };
    for shininess in [0.0, 10.0] {
        assert_within_bounds(&single(shiny(shininess), light), &positions, &normals);
    }
}

/// Lights touching the vertex, very near and very far, with coefficients
/// up to past f32's range (where `inf · 0` at distance 0 must not be NaN).
#[test]
fn lights_very_near_and_very_far() {
    for distance in [0.0, 1e-20, 1e-10, 1.0, 1e10, 1e20] {
        for k in [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1e-30, 0.0, 1e30],
            [1.0, 1e39, 0.0],
            [1.0, 0.0, 1e300],
            [1e39, 0.0, 0.0],
            [0.0, 1e300, 1e300],
        ] {
            let light = Light {
                position: LightPosition::Positional(DVec3::new(0.0, distance, distance)),
                attenuation: k,
                ..Light::default()
            };
            let positions = vec![DVec3::ZERO];
            let normals = vec![DVec3::new(0.0, 1.0, 1.0)];
            assert_within_bounds(&single(shiny(8.0), light), &positions, &normals);
        }
    }
}

#[test]
fn huge_coordinates_keep_the_lights_direction() {
    let base = DVec3::splat(1e7);
    let light = Light {
        position: LightPosition::Positional(base + DVec3::new(0.3, 0.4, 0.866)),
        attenuation: [1.0, 0.1, 0.01],
        ..Light::default()
    };
    let mut scene = single(shiny(32.0), light);
    scene.lights.viewer = Viewer::Local(base + DVec3::new(0.0, 0.0, 2.0));
    let positions: Vec<DVec3> = (0..100)
        .map(|i| base + DVec3::new(i as f64 * 1e-3, 0.0, 0.0))
        .collect();
    let normals = vec![DVec3::Z; positions.len()];
    assert_within_bounds(&scene, &positions, &normals);
}

#[test]
fn tiny_and_huge_normals_with_normalize_on_and_off() {
    for normalize in [true, false] {
        let lengths: &[f64] = if normalize {
            &[1e-300, 1e-30, 1.0, 1e30, 1e300]
        } else {
            &[1e-30, 1e-3, 1.0, 2.0]
        };
        let normals: Vec<DVec3> = lengths
            .iter()
            .map(|&l| DVec3::new(0.0, 0.6, 0.8) * l)
            .collect();
        let positions = vec![DVec3::ZERO; normals.len()];
        let mut scene = single(shiny(4.0), Light::default());
        scene.lights.model.normalize_normals = normalize;
        scene.material.front.specular = DVec4::splat(0.1);
        assert_within_bounds(&scene, &positions, &normals);
    }
}

#[test]
fn powers_that_underflow_stay_zero() {
    // (n·ĥ)^128 for n·ĥ ~ 0.01 is far below f32's normal range.
    let (p, n) = fan(200, 1.55);
    assert_within_bounds(&single(shiny(128.0), Light::default()), &p, &n);
}

// The fast tier lights a block from a light at a point without normalising
// `VP_pli` (its `n·VP_pli`, `ĥ` and spot cosine come from the unscaled
// `P_pli − V`, and its attenuation from a reciprocal of its own) wherever
// every vertex of the block is at a squared distance within 1e-30..1e30 of
// the light; the tests below hold it to its bound where those
// approximations are weakest, on batches of several blocks.

/// A light at `(0, 0, height)` over a patch of the plane z = 0, seen by
/// a local viewer above it (`local`) or from infinity, with the normals of
/// `fan` tilted about the y axis so that `n·ĥ` sweeps the highlight.
fn point_over_a_patch(
    light: Light,
    local: bool,
    shininess: f64,
) -> (Scene, Vec<DVec3>, Vec<DVec3>) {
    let mut scene = single(
        Material {
            diffuse: DVec4::splat(0.8),
            specular: DVec4::ONE,
            shininess,
            ..Material::default()
        },
        light,
    );
    if local {
        scene.lights.model.local_viewer = true;
        scene.lights.viewer = Viewer::Local(DVec3::new(0.7, -0.3, 3.0));
    }
    let (_, fan_normals) = fan(16, 1.2);
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..24 {
        for (j, n) in fan_normals.iter().enumerate() {
            let x = (i as f64 - 12.0) / 4.0;
            positions.push(DVec3::new(x, (j as f64 - 8.0) / 8.0, 0.0));
            normals.push(*n);
        }
    }
    (scene, positions, normals)
}

fn point_light(at: DVec3, spot: Spot) -> Light {
    Light {
        position: LightPosition::Positional(at),
        attenuation: [1.0, 0.2, 0.05],
        spot,
        ..Light::default()
    }
}

/// The vertices of `positions` and `normals` (paired) where the reference
/// is continuous and its derivative bounded, so that a bound on the
/// absolute error can hold in f32: away from the step of `f_i` at
/// `n·VP = 0`, from the cone's edge, and, since `c^s` for `s < 1` rises
/// infinitely steeply from `c = 0`, from a zero specular or spot cosine.
/// Computed in f64 from the scene's one light and its viewer.
fn well_conditioned(
    scene: &Scene,
    positions: &[DVec3],
    normals: &[DVec3],
) -> (Vec<DVec3>, Vec<DVec3>) {
    let light = scene.lights.lights()[0];
    let LightPosition::Positional(at) = light.position else {
        unreachable!("a light at a point")
    };
    positions
        .iter()
        .zip(normals)
        .filter(|&(&p, &n)| {
            let (n, vp) = (n.normalize(), (at - p).normalize());
            let vp_e = match scene.lights.viewer {
                Viewer::Local(eye) => (eye - p).normalize(),
                Viewer::Infinite(direction) => direction.normalize(),
            };
            let n_dot_h = n.dot((vp + vp_e).normalize());
            let spot = (-vp).dot(light.spot.direction.normalize());
            let edge = light.spot.cutoff.to_radians().cos();
            let away = |x: f64, from: f64, by: f64| (x - from).abs() > by;
            away(n.dot(vp), 0.0, 1e-4)
                && away(n_dot_h, 0.0, 1e-3)
                && (!light.spot.is_cone() || (away(spot, edge, 1e-5) && away(spot, 0.0, 1e-3)))
        })
        .map(|(p, n)| (*p, *n))
        .unzip()
}

/// [`assert_within_bounds`] on the [`well_conditioned`] vertices.
fn assert_within_bounds_where_conditioned(scene: &Scene, positions: &[DVec3], normals: &[DVec3]) {
    let (p, n) = well_conditioned(scene, positions, normals);
    assert!(!p.is_empty(), "no vertex left");
    assert_within_bounds(scene, &p, &n);
}

/// Shininess and spot exponents at the ends of GL's range: near 0, where
/// `c^s` rises steeply from `c = 0` and the powers are logarithms and
/// exponentials, and near 128, where a power multiplies the relative error
/// of its cosine by up to 64.
#[test]
fn fast_point_exponents_near_0_and_128() {
    for exponent in [0.0, 1e-4, 0.01, 0.5, 1.0, 2.0, 126.0, 127.9, 128.0] {
        let spot = Spot {
            direction: DVec3::new(0.1, 0.0, -1.0).normalize(),
            exponent,
            cutoff: 60.0,
        };
        for local in [false, true] {
            let light = point_light(DVec3::new(0.3, 0.1, 2.0), spot);
            let (scene, p, n) = point_over_a_patch(light, local, exponent);
            assert_within_bounds_where_conditioned(&scene, &p, &n);
            let light = point_light(DVec3::new(0.3, 0.1, 2.0), Spot::default());
            let (scene, p, n) = point_over_a_patch(light, local, exponent);
            assert_within_bounds_where_conditioned(&scene, &p, &n);
        }
    }
}

/// Cones whose edge crosses the patch, from the narrowest (0°, lit only on
/// its axis) through the tier's switch to a test on `cos²` (30°) to 90°,
/// where the vertices behind the light are just outside.
#[test]
fn fast_point_cutoffs_near_90_and_0() {
    for cutoff in [
        0.0, 1e-3, 0.5, 29.9, 30.0, 30.1, 45.0, 60.0, 89.9, 89.999, 90.0,
    ] {
        for height in [1.0, 1e-3] {
            let spot = Spot {
                direction: DVec3::new(0.0, 0.0, -1.0),
                exponent: 4.0,
                cutoff,
            };
            for local in [false, true] {
                // With a height of 1e-3 most of the patch lies near 90° off
                // the axis, and the light's own point is a vertex.
                let light = point_light(DVec3::new(0.0, 0.0, height), spot);
                let (scene, p, n) = point_over_a_patch(light, local, 16.0);
                assert_within_bounds_where_conditioned(&scene, &p, &n);
            }
        }
    }
}

/// Lights whose squared distance to the vertices lies near the ends of
/// the range the fast path takes unscaled (1e-30 and 1e30), on either side,
/// with all the lanes of a block on one side and spread across it, with
/// attenuations whose denominators reach the clamp at both ends.
#[test]
fn fast_point_distances_near_the_thresholds() {
    for distance in [
        0.5e-15, 0.99e-15, 1.01e-15, 2e-15, 0.5e15, 0.99e15, 1.01e15, 2e15,
    ] {
        for k in [
            [1.0, 0.0, 0.0],
            [1e-10, 0.0, 1e7],
            [1.0, 1e-16, 1e-30],
            [0.0, 0.0, 1.0],
        ] {
            let light = Light {
                attenuation: k,
                ..point_light(DVec3::new(0.0, 0.6, 0.8) * distance, Spot::default())
            };
            let mut scene = single(shiny(32.0), light);
            scene.lights.model.local_viewer = true;
            scene.lights.viewer = Viewer::Local(DVec3::new(0.0, 0.0, 2.0));
            // Vertices at about `distance` from the light, tilted normals;
            // then vertices from 1 to 3.2 times as far, so that the
            // threshold falls between the lanes of one block.
            let (_, normals) = fan(200, 1.5);
            let near: Vec<DVec3> = (0..200)
                .map(|i| DVec3::X * (i as f64 * 1e-3 * distance))
                .collect();
            assert_within_bounds(&scene, &near, &normals);
            let spread: Vec<DVec3> = (0..200)
                .map(|i| DVec3::X * ((i % 4) as f64 * distance))
                .collect();
            assert_within_bounds(&scene, &spread, &normals);
        }
    }
}

/// Normals of lengths from 1e-300 to 1e300, normalised, under a light at a
/// point seen by a local viewer: the fast path's `n·VP_e` is taken once per
/// block from the normalised normal, and negated with it for the back.
#[test]
fn fast_point_tiny_and_huge_normals() {
    let lengths = [1e-300, 1e-30, 1e-3, 1.0, 1e3, 1e30, 1e300];
    let normals: Vec<DVec3> = (0..128)
        .map(|i| {
            let a = i as f64 / 128.0 * 3.0 - 1.5;
            DVec3::new(a.sin(), 0.2, a.cos()) * lengths[i % lengths.len()]
        })
        .collect();
    let positions: Vec<DVec3> = (0..128)
        .map(|i| DVec3::new(i as f64 / 64.0 - 1.0, 0.0, 0.0))
        .collect();
    for two_side in [false, true] {
        let light = point_light(DVec3::new(0.2, 0.0, 1.5), Spot::default());
        let (mut scene, _, _) = point_over_a_patch(light, true, 64.0);
        scene.lights.model.two_side = two_side;
        assert_within_bounds(&scene, &positions, &normals);
    }
}

/// Eight lights at points whose terms add up to nearly 1 on the patch, at
/// the largest exponents whose powers the fast tier's one pass takes from
/// the estimate of a reciprocal alone (a shininess of 32, a spot exponent
/// of 16) and just above them (34 and 18, with a Newton step): the
/// relative errors of each light's terms add, and eight lights' terms add
/// into one colour below its clamp.
#[test]
fn fast_point_estimates_at_their_largest_exponents_under_eight_lights() {
    for (shininess, exponent) in [(32.0, 16.0), (34.0, 18.0), (32.0, 0.0), (128.0, 128.0)] {
        for local in [false, true] {
            let lights: Vec<Light> = (0..8)
                .map(|i| {
                    let at = DVec3::new(i as f64 * 0.7 - 2.5, 0.4, 1.5);
                    let spot = Spot {
                        direction: DVec3::new(0.1, -0.1, -1.0).normalize(),
                        exponent,
                        cutoff: 75.0,
                    };
                    Light {
                        ambient: DVec4::splat(0.01),
                        diffuse: DVec4::splat(0.09),
                        specular: DVec4::splat(0.11),
                        ..point_light(at, spot)
                    }
                })
                .collect();
            let (mut scene, mut p, mut n) = point_over_a_patch(lights[0], local, shininess);
            // Away from each light's steps, as `well_conditioned` keeps them
            // for one.
            for light in &lights {
                let one = Scene {
                    lights: with_lights(&scene.lights, vec![*light]),
                    material: scene.material,
                };
                (p, n) = well_conditioned(&one, &p, &n);
            }
            scene.lights = with_lights(&scene.lights, lights);
            assert!(p.len() > 100, "{} vertices left", p.len());
            assert_within_bounds(&scene, &p, &n);
        }
    }
}
