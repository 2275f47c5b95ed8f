//! The explanation of a colour: `Breakdown` (every term before clamping) and
//! `Summary` (statistics of the terms over a batch).

use glam::{DVec3, DVec4};
use glint_lighting::terms::{Breakdown, LightTerms, Summary};
use glint_lighting::{ColorControl, Light, LightModel, LightPosition, Material};

use super::support::{R2, black_light, black_material, dark_model, eye_space, front_terms, grey};

fn terms(
    ambient: DVec3,
    diffuse: DVec3,
    specular: DVec3,
    attenuation: f64,
    spot: f64,
) -> LightTerms {
    LightTerms {
        ambient,
        diffuse,
        specular,
        attenuation,
        spot,
    }
}

fn v3(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// A breakdown written out by hand, two lights.
fn two_light_breakdown() -> Breakdown {
    Breakdown {
        emission: v3(0.1, 0.0, 0.0),
        global_ambient: v3(0.0, 0.2, 0.0),
        lights: vec![
            terms(
                v3(0.1, 0.1, 0.1),
                v3(0.2, 0.3, 0.4),
                v3(0.5, 0.0, 0.0),
                1.0,
                1.0,
            ),
            terms(
                v3(0.0, 0.0, 0.05),
                v3(-0.1, 0.1, 0.0),
                v3(0.0, 0.25, 0.5),
                0.5,
                0.5,
            ),
        ],
    }
}

/// unclamped = e + a_cm·a_cs + Σ (ambient + diffuse + specular):
/// r: 0.1 + 0 + (0.1 + 0.2 + 0.5) + (0 − 0.1 + 0)  = 0.8
/// g: 0 + 0.2 + (0.1 + 0.3 + 0)   + (0 + 0.1 + 0.25) = 0.95
/// b: 0 + 0   + (0.1 + 0.4 + 0)   + (0.05 + 0 + 0.5) = 1.05
/// primary leaves out the specular terms, secondary is their sum.
#[test]
fn unclamped_is_the_sum_of_all_terms() {
    let b = two_light_breakdown();
    assert_close!(b.unclamped(), v3(0.8, 0.95, 1.05));
    assert_close!(b.primary(), v3(0.8 - 0.5, 0.95 - 0.25, 1.05 - 0.5));
    assert_close!(b.secondary(), v3(0.5, 0.25, 0.5));
    assert!(b.was_clamped()); // blue is 1.05
}

/// With every part in [0, 1] the controls agree:
/// Single: clamp(0.8, 0.95, 1.05) = (0.8, 0.95, 1);
/// Separate: clamp(clamp(0.3, 0.7, 0.55) + clamp(0.5, 0.25, 0.5)) = the same.
/// With a primary above 1 and a negative secondary they differ (below).
#[test]
fn color_applies_the_colour_control_and_the_alpha() {
    let b = two_light_breakdown();
    assert_close!(
        b.color(ColorControl::Single, 0.5),
        DVec4::new(0.8, 0.95, 1.0, 0.5)
    );
    assert_close!(
        b.color(ColorControl::SeparateSpecular, 0.5),
        DVec4::new(0.8, 0.95, 1.0, 0.5)
    );

    // primary (1.2, 0.5, 0.2), secondary (−0.4, 0.7, 0.9)
    let b = Breakdown {
        emission: v3(1.2, 0.5, 0.2),
        global_ambient: DVec3::ZERO,
        lights: vec![terms(
            DVec3::ZERO,
            DVec3::ZERO,
            v3(-0.4, 0.7, 0.9),
            1.0,
            1.0,
        )],
    };
    // Single: clamp(0.8, 1.2, 1.1) = (0.8, 1, 1).
    assert_close!(
        b.color(ColorControl::Single, 1.0),
        DVec4::new(0.8, 1.0, 1.0, 1.0)
    );
    // Separate: clamp((1, 0.5, 0.2) + (0, 0.7, 0.9)) = clamp(1, 1.2, 1.1) = (1, 1, 1).
    assert_close!(
        b.color(ColorControl::SeparateSpecular, 1.0),
        DVec4::new(1.0, 1.0, 1.0, 1.0)
    );
    // Alpha is clamped too.
    assert_eq!(b.color(ColorControl::Single, 2.0).w, 1.0);
    assert_eq!(b.color(ColorControl::Single, -1.0).w, 0.0);
}

/// `was_clamped` is true exactly when a channel of the sum lies outside
/// [0, 1]: 0 and 1 themselves are inside.
#[test]
fn was_clamped_at_the_boundaries() {
    let with_emission = |e: DVec3| Breakdown {
        emission: e,
        ..Breakdown::default()
    };
    assert!(!with_emission(v3(0.0, 1.0, 0.5)).was_clamped());
    assert!(!with_emission(v3(1.0, 1.0, 1.0)).was_clamped());
    assert!(!with_emission(DVec3::ZERO).was_clamped());
    assert!(with_emission(v3(0.5, 1.0 + 1e-12, 0.5)).was_clamped());
    assert!(with_emission(v3(0.5, 0.5, -1e-12)).was_clamped());
}

/// The breakdown of an evaluated vertex adds up to the colour it explains.
/// GL's default material and model, n = +z, two lights:
/// - GL_LIGHT0 overhead: diffuse 0.8·1, specular 0 (s_cm = 0);
/// - a positional light at (0,0,2) with a_cli = 0.5, d_cli = 0.5,
///   k = (0,1,0): att = 1/2; ambient ½·0.2·0.5 = 0.05, diffuse ½·0.8·0.5 = 0.2.
///
/// unclamped = 0.04 + 0.8 + 0.05 + 0.2 = 1.09 per channel; the colour is 1.
#[test]
fn evaluated_breakdown_adds_up() {
    let second = Light {
        ambient: grey(0.5),
        diffuse: grey(0.5),
        attenuation: [0.0, 1.0, 0.0],
        ..black_light(LightPosition::Positional(DVec3::new(0.0, 0.0, 2.0)))
    };
    let scene = eye_space(
        LightModel::default(),
        Material::default(),
        vec![Light::default(), second],
    );
    let b = front_terms(&scene, DVec3::ZERO, DVec3::Z);
    assert_close!(b.emission, DVec3::ZERO);
    assert_close!(b.global_ambient, DVec3::splat(0.04));
    assert_close!(b.lights[0].diffuse, DVec3::splat(0.8));
    assert_close!(b.lights[1].attenuation, 0.5);
    assert_close!(b.lights[1].ambient, DVec3::splat(0.05));
    assert_close!(b.lights[1].diffuse, DVec3::splat(0.2));
    let sum = b.emission
        + b.global_ambient
        + b.lights
            .iter()
            .map(|l| l.ambient + l.diffuse + l.specular)
            .sum::<DVec3>();
    assert_close!(b.unclamped(), sum);
    assert_close!(b.unclamped(), DVec3::splat(0.04 + 0.8 + 0.05 + 0.2));
    assert!(b.was_clamped());
}

/// Three breakdowns of two lights each, written out by hand.
///
/// | # | emission    | global   | L0 ambient  | L0 diffuse      | L0 specular | L0 att, spot | L1 diffuse          | L1 att, spot | sum (r,g,b)       |
/// |---|-------------|----------|-------------|-----------------|-------------|--------------|---------------------|--------------|-------------------|
/// | 1 | .1 .2 .3    | 0        | .1 0 0      | .2 .2 .2        | 0           | 1, 1         | −.1 −.2 −.3         | 1, .5        | .3 .2 .2   inside |
/// | 2 | .1 .2 .3    | .1 .1 .1 | 0           | .9 .5 .1        | .6 0 0      | .5, .25      | −.5 −.1 −.2         | 2, 1         | 1.2 .7 .3  clamped|
/// | 3 | .1 .2 .3    | 0        | 0           | −.5 0 0         | 0           | 2, 0         | −.3 −.3 −.1         | 4, 0         | −.7 −.1 .2 clamped|
///
/// Means are sums over 3; the maxima are per channel (L0 diffuse g comes from
/// #2, b from #1), and L1's maxima are negative: the largest of negative
/// values, not 0.
#[test]
fn summary_of_a_small_batch() {
    let zero = DVec3::ZERO;
    let batch = [
        Breakdown {
            emission: v3(0.1, 0.2, 0.3),
            global_ambient: zero,
            lights: vec![
                terms(v3(0.1, 0.0, 0.0), v3(0.2, 0.2, 0.2), zero, 1.0, 1.0),
                terms(zero, v3(-0.1, -0.2, -0.3), zero, 1.0, 0.5),
            ],
        },
        Breakdown {
            emission: v3(0.1, 0.2, 0.3),
            global_ambient: v3(0.1, 0.1, 0.1),
            lights: vec![
                terms(zero, v3(0.9, 0.5, 0.1), v3(0.6, 0.0, 0.0), 0.5, 0.25),
                terms(zero, v3(-0.5, -0.1, -0.2), zero, 2.0, 1.0),
            ],
        },
        Breakdown {
            emission: v3(0.1, 0.2, 0.3),
            global_ambient: zero,
            lights: vec![
                terms(zero, v3(-0.5, 0.0, 0.0), zero, 2.0, 0.0),
                terms(zero, v3(-0.3, -0.3, -0.1), zero, 4.0, 0.0),
            ],
        },
    ];
    // The sums in the table, so that a wrong table fails here and not below.
    assert_close!(batch[0].unclamped(), v3(0.3, 0.2, 0.2));
    assert_close!(batch[1].unclamped(), v3(1.2, 0.7, 0.3));
    assert_close!(batch[2].unclamped(), v3(-0.7, -0.1, 0.2));

    let s = Summary::of(&batch).expect("a non-empty batch has a summary");
    assert_eq!(s.count, 3);
    assert_eq!(s.lights.len(), 2);
    // #2 (red 1.2) and #3 (red −0.7, green −0.1) are clamped.
    assert_close!(s.clamped_share, 2.0 / 3.0);

    assert_close!(s.emission.mean, v3(0.1, 0.2, 0.3));
    assert_close!(s.emission.max, v3(0.1, 0.2, 0.3));
    assert_close!(s.global_ambient.mean, v3(0.1, 0.1, 0.1) / 3.0);
    assert_close!(s.global_ambient.max, v3(0.1, 0.1, 0.1));

    let l0 = &s.lights[0];
    assert_close!(l0.ambient.mean, v3(0.1 / 3.0, 0.0, 0.0));
    assert_close!(l0.ambient.max, v3(0.1, 0.0, 0.0));
    assert_close!(
        l0.diffuse.mean,
        v3(
            (0.2 + 0.9 - 0.5) / 3.0,
            (0.2 + 0.5) / 3.0,
            (0.2 + 0.1) / 3.0
        )
    );
    assert_close!(l0.diffuse.max, v3(0.9, 0.5, 0.2));
    assert_close!(l0.specular.mean, v3(0.6 / 3.0, 0.0, 0.0));
    assert_close!(l0.specular.max, v3(0.6, 0.0, 0.0));
    assert_close!(l0.attenuation.mean, (1.0 + 0.5 + 2.0) / 3.0);
    assert_close!(l0.attenuation.max, 2.0);
    assert_close!(l0.spot.mean, (1.0 + 0.25 + 0.0) / 3.0);
    assert_close!(l0.spot.max, 1.0);

    let l1 = &s.lights[1];
    assert_close!(l1.diffuse.mean, v3(-0.9 / 3.0, -0.6 / 3.0, -0.6 / 3.0));
    assert_close!(l1.diffuse.max, v3(-0.1, -0.1, -0.1));
    assert_close!(l1.ambient.max, zero);
    assert_close!(l1.attenuation.mean, (1.0 + 2.0 + 4.0) / 3.0);
    assert_close!(l1.attenuation.max, 4.0);
    assert_close!(l1.spot.mean, 0.5);
    assert_close!(l1.spot.max, 1.0);
}

/// The clamped share counts breakdowns, not channels: of four breakdowns, one
/// out of range on one channel and one on all three give 2/4.
#[test]
fn clamped_share_counts_breakdowns() {
    let with_emission = |e: DVec3| Breakdown {
        emission: e,
        ..Breakdown::default()
    };
    let batch = [
        with_emission(v3(0.5, 0.5, 0.5)),
        with_emission(v3(2.0, 0.5, 0.5)),
        with_emission(v3(-1.0, 2.0, 3.0)),
        with_emission(v3(1.0, 0.0, 1.0)),
    ];
    let s = Summary::of(&batch).unwrap();
    assert_eq!(s.count, 4);
    assert!(s.lights.is_empty());
    assert_close!(s.clamped_share, 2.0 / 4.0);
    assert_close!(s.emission.mean, v3(2.5 / 4.0, 3.0 / 4.0, 5.0 / 4.0));
    assert_close!(s.emission.max, v3(2.0, 2.0, 3.0));
}

#[test]
fn summary_of_an_empty_batch_is_none() {
    assert_eq!(Summary::of(&[] as &[Breakdown]), None);
    assert_eq!(Summary::of(std::iter::empty::<&Breakdown>()), None);
}

/// A summary over evaluated vertices. One positional light at (0,0,2) with
/// d_cli = 1, k = (0,1,0) (att = 1/d), on d_cm = 0.8, vertices on the z axis:
///
/// | vertex      | normal        | d | att | n·VP | diffuse      |
/// |-------------|---------------|---|-----|------|--------------|
/// | (0,0,0)     | +z            | 2 | 1/2 | 1    | 0.8/2        |
/// | (0,0,-2)    | (1,0,1)/√2    | 4 | 1/4 | 1/√2 | 0.8/(4√2)    |
/// | (0,0,1)     | -z            | 1 | 1   | 0    | 0            |
#[test]
fn summary_of_evaluated_vertices() {
    let light = Light {
        diffuse: grey(1.0),
        attenuation: [0.0, 1.0, 0.0],
        ..black_light(LightPosition::Positional(DVec3::new(0.0, 0.0, 2.0)))
    };
    let material = Material {
        diffuse: grey(0.8),
        ..black_material()
    };
    let scene = eye_space(dark_model(), material, vec![light]);
    let batch: Vec<Breakdown> = [
        (v3(0.0, 0.0, 0.0), DVec3::Z),
        (v3(0.0, 0.0, -2.0), DVec3::new(R2, 0.0, R2)),
        (v3(0.0, 0.0, 1.0), DVec3::NEG_Z),
    ]
    .into_iter()
    .map(|(v, n)| front_terms(&scene, v, n))
    .collect();
    let s = Summary::of(&batch).unwrap();
    assert_eq!(s.count, 3);
    let l = &s.lights[0];
    assert_close!(l.attenuation.mean, (0.5 + 0.25 + 1.0) / 3.0);
    assert_close!(l.attenuation.max, 1.0);
    assert_close!(l.spot.mean, 1.0);
    assert_close!(
        l.diffuse.mean,
        DVec3::splat((0.8 / 2.0 + 0.8 / 4.0 * R2) / 3.0)
    );
    assert_close!(l.diffuse.max, DVec3::splat(0.4));
    assert_close!(l.specular.max, DVec3::ZERO);
    assert_close!(s.clamped_share, 0.0);
}
