//! Adaptive sampling: a flat image takes the fewest samples (a pixel's four
//! corners and its centre), an edge more, the smooth inside of a lit
//! sphere no more than a flat image, and a pixel's samples depend on its
//! own coordinates only (a region is the same crop of the whole image).

use glam::{DVec3, DVec4};
use glint_trace::film::{self, Moments, SamplePattern, SetMoments};
use glint_trace::{Region, RenderScene, Renderer, Samples, Visibility};
use serde_json::{Value, json};

use super::support::{Cam, ray_sphere, scene_of};
use crate::support::Rng;

const TOLERANCE: f64 = 1.0 / 255.0;

fn adaptive(mut request: Value) -> RenderScene {
    request["samples"] = json!(1);
    let mut scene = scene_of(&request);
    scene.samples = Samples::Adaptive {
        max: 64,
        tolerance: TOLERANCE,
    };
    scene
}

/// A red sphere on a blue floor under one light, 48×36.
fn edges() -> Value {
    json!({
        "materials": { "red": { "diffuse": [0.9, 0.1, 0.1] }, "blue": { "diffuse": [0.1, 0.2, 0.9] } },
        "lights": [{ "position": [1, 2, 3, 0] }],
        "camera": { "eye": [0, 1.5, 4], "target": [0, 0.5, 0], "up": [0, 1, 0],
                    "fov_y": 40, "width": 48, "height": 36 },
        "objects": [
            { "sphere": { "center": [0, 0.7, 0], "radius": 0.7 }, "material": "red" },
            { "plane": { "point": [0, 0, 0], "normal": [0, 1, 0] }, "material": "blue" },
        ],
        "background": [0.0, 0.0, 0.0, 1.0],
    })
}

#[test]
fn a_flat_image_takes_its_corners_and_centre_per_pixel() {
    // Nothing to hit: every sample is the background.
    let mut request = edges();
    request["objects"] = json!([]);
    request["background"] = json!([0.2, 0.4, 0.6, 1.0]);
    let scene = adaptive(request);
    let frame = Renderer::new(&scene).render(false, &|| false).unwrap();
    assert_eq!(frame.sampling.mean, 5.0, "{:?}", frame.sampling);
    assert_eq!(frame.sampling.max, 5);
    assert_eq!(frame.sampling.estimated_error, Some(0.0));
    let want = [51, 102, 153, 255];
    assert!(frame.rgba.chunks_exact(4).all(|p| p == want));
}

#[test]
fn an_edge_takes_more_samples_than_the_inside() {
    let scene = adaptive(edges());
    let stats = Renderer::new(&scene)
        .render(false, &|| false)
        .unwrap()
        .sampling;
    assert_eq!(
        stats.max, 64,
        "an edge pixel that never settles takes them all"
    );
    assert!(stats.mean > 5.0 && stats.mean < 16.0, "{stats:?}");
    // The centre of the sphere's disc (the image's middle) and the far
    // floor's inside take five; a pixel on the sphere's outline more.
    let pixel_samples = |x: u32, y: u32| {
        let mut one = scene.clone();
        one.region = Region {
            x,
            y,
            width: 1,
            height: 1,
        };
        Renderer::new(&one)
            .render(false, &|| false)
            .unwrap()
            .sampling
            .max
    };
    assert_eq!(pixel_samples(24, 20), 5, "inside the sphere");
    assert_eq!(pixel_samples(3, 33), 5, "inside the floor");
    // Along row 20, the sphere's outline, found by an independent test of
    // the pixels' centre rays: the first pixel whose ray meets the sphere.
    let cam = Cam {
        eye: DVec3::new(0.0, 1.5, 4.0),
        target: DVec3::new(0.0, 0.5, 0.0),
        up: DVec3::Y,
        fov_y: 40.0,
        width: 48,
        height: 36,
    };
    let on_sphere = |x: u32| {
        ray_sphere(
            cam.eye,
            cam.centre_dir(x, 20),
            DVec3::new(0.0, 0.7, 0.0),
            0.7,
        )
        .is_some()
    };
    let edge = (1..24)
        .find(|&x| on_sphere(x) && !on_sphere(x - 1))
        .expect("the row crosses the sphere's outline");
    let around = (edge - 1..=edge)
        .map(|x| pixel_samples(x, 20))
        .max()
        .unwrap();
    assert!(
        around > 4,
        "the outline takes more than the corners: {around}"
    );
}

#[test]
fn adaptive_regions_are_crops_of_the_whole_image() {
    let scene = adaptive(edges());
    let whole = Renderer::new(&scene).render(false, &|| false).unwrap();
    for (x, y, width, height) in [
        (0, 0, 48, 36),
        (5, 3, 17, 11),
        (16, 16, 16, 16),
        (47, 35, 1, 1),
    ] {
        let mut tile = scene.clone();
        tile.region = Region {
            x,
            y,
            width,
            height,
        };
        let part = Renderer::new(&tile).render(false, &|| false).unwrap();
        for row in 0..height {
            let from = ((y + row) * 48 + x) as usize * 4;
            let expected = &whole.rgba[from..from + width as usize * 4];
            let start = (row * width) as usize * 4;
            assert_eq!(
                &part.rgba[start..start + width as usize * 4],
                expected,
                "region ({x}, {y}) {width}×{height}, row {row}"
            );
        }
    }
}

#[test]
fn adaptive_renders_rasterized_and_traced_are_the_same() {
    let mut request = edges();
    request["objects"][1] = json!({ "mesh": {
        "positions": [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]],
        "indices": [0, 2, 1, 0, 3, 2] }, "material": "blue" });
    request["shading"] = json!("per_vertex");
    let scene = adaptive(request);
    let a = Renderer::with_visibility(&scene, Visibility::Rasterized)
        .render(true, &|| false)
        .unwrap();
    let b = Renderer::with_visibility(&scene, Visibility::Traced)
        .render(true, &|| false)
        .unwrap();
    assert!(a.rgba == b.rgba);
    assert_eq!(a.sampling, b.sampling);
}

/// A frame's term summary is of its pixels' centres, whatever its samples:
/// with one sample per pixel and with adaptive sampling, whose samples
/// include the centres, the terms read the surfaces and shadow rays the
/// samples traced; with four samples, none of them at a centre, each
/// centre is traced again. The three summarise alike, bit for bit; asking
/// for the terms changes no pixel, and where every pixel is lit per pixel
/// it traces no ray more than the samples did. Scenes with shadows from
/// two lights (one directional, one positional), at every precision, with
/// spheres and planes beside a mesh (the traced samples) and with the mesh
/// alone (the rasterized ones).
#[test]
fn the_term_summary_is_of_the_centres_whatever_the_samples() {
    let triangle = json!({ "mesh": {
        "positions": [[-1.4, 0.1, 0.5], [-0.2, 0.1, 0.9], [-0.8, 1.2, 0.6]],
        "indices": [0, 1, 2] }, "material": "red" });
    let samplings = [
        Samples::Uniform(1),
        Samples::Uniform(4),
        Samples::Adaptive {
            max: 64,
            tolerance: TOLERANCE,
        },
    ];
    for mesh_alone in [false, true] {
        for shading in ["per_pixel", "per_vertex"] {
            for precision in ["reference", "accurate", "fast"] {
                let mut request = edges();
                request["shadows"] = json!(true);
                request["shading"] = json!(shading);
                request["precision"] = json!(precision);
                request["lights"] = json!([
                    { "position": [1, 2, 3, 0] },
                    { "position": [-1.5, 2.5, 1.5, 1], "attenuation": [1, 0.1, 0] },
                ]);
                if mesh_alone {
                    request["objects"] = json!([triangle]);
                } else {
                    request["objects"]
                        .as_array_mut()
                        .unwrap()
                        .push(triangle.clone());
                }
                let case = format!("{shading}, {precision}, mesh alone: {mesh_alone}");
                let mut summaries = Vec::new();
                for samples in samplings {
                    let mut scene = scene_of(&request);
                    scene.samples = samples;
                    let (with, without) = (Renderer::new(&scene), Renderer::new(&scene));
                    let terms = with.render(true, &|| false).unwrap();
                    let image = without.render(false, &|| false).unwrap();
                    assert!(terms.rgba == image.rgba, "{case}, {samples:?}: the image");
                    if samples == Samples::Uniform(4) {
                        assert!(with.rays() > without.rays(), "{case}: the centres");
                    } else if shading == "per_pixel" {
                        assert_eq!(with.rays(), without.rays(), "{case}, {samples:?}: rays");
                    }
                    summaries.push(format!("{:?}", terms.summary.expect("some pixel is lit")));
                }
                assert_eq!(
                    summaries[0], summaries[1],
                    "{case}: one sample against four"
                );
                assert_eq!(summaries[2], summaries[1], "{case}: adaptive against four");
            }
        }
    }
}

/// With the tolerance at its largest, more pixels settle at their corners
/// than at 1/255, and none takes more samples.
#[test]
fn a_looser_tolerance_takes_fewer_samples() {
    let tight = adaptive(edges());
    let mut loose = tight.clone();
    loose.samples = Samples::Adaptive {
        max: 64,
        tolerance: glint_trace::MAX_TOLERANCE,
    };
    let tight = Renderer::new(&tight)
        .render(false, &|| false)
        .unwrap()
        .sampling;
    let loose = Renderer::new(&loose)
        .render(false, &|| false)
        .unwrap()
        .sampling;
    assert!(loose.mean < tight.mean, "{loose:?} against {tight:?}");
}

#[test]
fn no_pixel_takes_more_than_max_samples() {
    // The first pattern (four corners and the centre) is five samples: a
    // `max` below it cannot start adaptive sampling, and must still bound
    // every pixel.
    for max in 1..=8 {
        let mut request = edges();
        request["samples"] = json!({ "max": max, "tolerance": TOLERANCE });
        let stats = Renderer::new(&scene_of(&request))
            .render(false, &|| false)
            .unwrap()
            .sampling;
        assert!(stats.max <= max, "max {max}: {stats:?}");
        assert!(stats.mean <= f64::from(max), "max {max}: {stats:?}");
    }
}

/// The colours of one full set of adaptive samples, sample `k` coloured by
/// `color` of its grid cell `(column, row)`.
fn set_colors(color: impl Fn(u32, u32) -> f64) -> Vec<DVec4> {
    let pattern = SamplePattern::new(film::SET);
    (0..film::SET)
        .map(|k| {
            let (column, row) = pattern.cell(k);
            DVec4::splat(color(column, row))
        })
        .collect()
}

#[test]
fn a_sets_error_ignores_what_differs_only_between_rows_and_columns() {
    // Cell means that are a function of the column plus one of the row (a
    // ramp, an edge along the grid) are no error of a stratified mean.
    let colors = set_colors(|column, row| 0.1 * f64::from(column) + 0.05 * f64::from(row * row));
    let mut set = SetMoments::default();
    set.add_set(&SamplePattern::new(film::SET), &colors);
    assert!(set.standard_error() < 1e-12, "{}", set.standard_error());
    // The iid estimate s²/n counts them: s² of the 16 values by hand.
    let values: Vec<f64> = colors.iter().map(|c| c.x).collect();
    let mean = values.iter().sum::<f64>() / 16.0;
    let s2 = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 15.0;
    assert!(s2 > 0.0);
    let iid = Moments::of(&colors).standard_error();
    assert!((iid - (s2 / 16.0).sqrt()).abs() < 1e-12, "{iid}");
}

#[test]
fn a_checkerboard_set_is_read_by_its_one_contrast() {
    // ±a alternating over the cells: the checkerboard contrast is 16·a,
    // the three others of the estimate 0, so Σσ²_h is estimated as
    // (16a)²/4 and the standard error of the 16 samples' mean as
    // √(64a²/(16·16)) = a/2.
    let a = 0.02;
    let colors = set_colors(|column, row| 0.5 + if (column + row) % 2 == 0 { a } else { -a });
    let mut set = SetMoments::default();
    set.add_set(&SamplePattern::new(film::SET), &colors);
    assert!(
        (set.standard_error() - a / 2.0).abs() < 1e-12,
        "{}",
        set.standard_error()
    );
    assert!((set.mean().x - 0.5).abs() < 1e-15);
}

#[test]
fn a_sets_error_of_independent_noise_is_its_standard_error() {
    // Every sample uniform in [0, 1) (variance 1/12): the squared estimate
    // of two sets' mean averages to the variance of that mean, 1/(12·32),
    // over many pixels.
    let mut rng = Rng::new(0x5e7);
    let pattern = SamplePattern::new(film::SET);
    let pixels = 4000;
    let mean_square: f64 = (0..pixels)
        .map(|_| {
            let mut set = SetMoments::default();
            for _ in 0..2 {
                let colors: Vec<DVec4> = (0..film::SET).map(|_| DVec4::splat(rng.unit())).collect();
                set.add_set(&pattern, &colors);
            }
            set.standard_error().powi(2)
        })
        .sum::<f64>()
        / f64::from(pixels);
    let variance = 1.0 / (12.0 * 32.0);
    assert!(
        (mean_square / variance - 1.0).abs() < 0.05,
        "{mean_square} against {variance}"
    );
}

#[test]
fn before_a_full_set_the_error_is_the_iid_one() {
    let colors: Vec<DVec4> = (0..8)
        .map(|k| DVec4::splat(f64::from(k * k) / 64.0))
        .collect();
    let mut set = SetMoments::default();
    set.add_set(&SamplePattern::new(8), &colors);
    assert_eq!(set.standard_error(), Moments::of(&colors).standard_error());
    assert_eq!(set.count(), 8);
}

#[test]
fn uniform_samples_count_every_pixel_and_estimate_an_error_from_more_than_one_sample() {
    for n in [1, 4] {
        let mut request = edges();
        request["samples"] = json!(n);
        let sampling = Renderer::new(&scene_of(&request))
            .render(false, &|| false)
            .unwrap()
            .sampling;
        assert_eq!(sampling.mean, f64::from(n), "{sampling:?}");
        assert_eq!(sampling.max, n);
        // One sample gives no spread to estimate an error from.
        assert_eq!(sampling.estimated_error.is_some(), n > 1, "{sampling:?}");
    }
}
