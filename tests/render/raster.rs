//! The rasterized visibility against the tracer it replaces: every sample's
//! hit, from the rasterizer's candidates and the exact test, is exactly the
//! hit of testing every primitive on the sample's ray (the f64 brute force
//! the BVH is checked against), and whole renders are the traced renders,
//! byte for byte.
//!
//! The scenes are made to break a rasterizer: random soups and height
//! fields with shared edges and vertices, degenerate and sliver triangles,
//! triangles behind the eye and across its plane, eyes inside and outside
//! the mesh's box, closed meshes seen from inside (watertight: every sample
//! hits), and images of 1×1, 1×N, N×1 and 4096×4096 pixels.

use glam::DVec3;
use glint_trace::camera::PinholeCamera;
use glint_trace::geometry::{Geometry, Hit, Ray};
use glint_trace::raster::{BIN, Raster, RasterScratch};
use glint_trace::{Camera, Mesh, Object, Region, Renderer, Shape, Visibility};
use serde_json::json;

use super::bvh::{random_objects, same, transformed};
use super::support::scene_of;
use crate::support::Rng;

/// Where in a pixel the samples of the tests lie: the centre, corners and
/// edges (exactly on the pixel grid) and two inside.
const OFFSETS: [(f64, f64); 6] = [
    (0.5, 0.5),
    (0.0, 0.0),
    (0.999_999_9, 0.5),
    (0.5, 0.0),
    (0.123, 0.877),
    (0.731, 0.269),
];

fn camera(eye: DVec3, target: DVec3, fov_y: f64, width: u32, height: u32) -> Camera {
    let up = if (target - eye).cross(DVec3::Y).length() > 1e-6 * (target - eye).length() {
        DVec3::Y
    } else {
        DVec3::X
    };
    Camera {
        eye,
        target,
        up,
        fov_y,
        width,
        height,
    }
}

fn whole(camera: &Camera) -> Region {
    Region {
        x: 0,
        y: 0,
        width: camera.width,
        height: camera.height,
    }
}

/// Checks the rasterizer's hits against brute force at every sample of
/// `OFFSETS` in the bins `pick` accepts (by bin column and row); returns
/// the samples checked and those that hit.
fn check(
    objects: &[Object],
    camera: &Camera,
    region: &Region,
    pick: impl Fn(u32, u32) -> bool,
    context: &str,
) -> (usize, usize) {
    check_at(objects, camera, region, pick, &OFFSETS, context)
}

/// [`check`] at the samples `offsets` of each pixel.
fn check_at(
    objects: &[Object],
    camera: &Camera,
    region: &Region,
    pick: impl Fn(u32, u32) -> bool,
    offsets: &[(f64, f64)],
    context: &str,
) -> (usize, usize) {
    let geometry = Geometry::new(objects);
    let pinhole = PinholeCamera::new(camera);
    let raster = Raster::new(&geometry, objects, &pinhole, camera, region)
        .unwrap_or_else(|_| panic!("{context}: the rasterizer declines the scene"));
    let mut scratch = RasterScratch::default();
    let (mut checked, mut hit) = (0, 0);
    for by in 0..region.height.div_ceil(BIN) {
        for bx in 0..region.width.div_ceil(BIN) {
            if !pick(bx, by) {
                continue;
            }
            let (x0, y0) = (region.x + bx * BIN, region.y + by * BIN);
            let mut points = Vec::new();
            for y in y0..(y0 + BIN).min(region.y + region.height) {
                for x in x0..(x0 + BIN).min(region.x + region.width) {
                    for &(ox, oy) in offsets {
                        points.push((f64::from(x) + ox, f64::from(y) + oy));
                    }
                }
            }
            let rays: Vec<Ray> = points.iter().map(|&(x, y)| pinhole.ray(x, y)).collect();
            let mut hits: Vec<Option<Hit>> = vec![None; rays.len()];
            raster.hits(&geometry, (x0, y0), &points, &rays, &mut hits, &mut scratch);
            for ((point, ray), found) in points.iter().zip(&rays).zip(&hits) {
                let brute = geometry.closest_hit_brute_force(ray);
                same(*found, brute, &format!("{context}, sample {point:?}"));
                checked += 1;
                hit += usize::from(found.is_some());
            }
        }
    }
    (checked, hit)
}

fn everywhere(_: u32, _: u32) -> bool {
    true
}

fn mesh(positions: Vec<DVec3>, indices: Vec<[u32; 3]>) -> Object {
    Object {
        shape: Shape::Mesh(Mesh {
            positions,
            normals: None,
            indices,
        }),
        material: 0,
    }
}

#[test]
fn raster_hits_equal_brute_force_from_outside_and_inside_the_box() {
    for seed in 0..4 {
        let mut rng = Rng::new(100 + seed);
        let objects = random_objects(&mut rng, 60);
        let centre = DVec3::splat(0.5);
        // Outside the box, looking in; inside it, looking every way.
        let eyes = [
            (centre + 2.5 * rng.unit_direction(), centre, 40.0),
            (rng.point(0.2, 0.8), rng.point(0.0, 1.0), 70.0),
            (rng.point(0.3, 0.7), rng.point(-1.0, 2.0), 100.0),
        ];
        for (i, (eye, target, fov)) in eyes.into_iter().enumerate() {
            let camera = camera(eye, target, fov, 53, 37);
            let context = format!("seed {seed}, eye {i}");
            let (checked, hit) = check(&objects, &camera, &whole(&camera), everywhere, &context);
            assert!(hit > checked / 20, "{context}: only {hit} of {checked} hit");
        }
    }
}

#[test]
fn raster_hits_equal_brute_force_at_any_scale_and_offset() {
    let mut rng = Rng::new(9);
    let objects = random_objects(&mut rng, 40);
    for (scale, offset) in [
        (1e-6, DVec3::splat(1e3)),
        (1e5, DVec3::new(-3e7, 1e6, 2e5)),
        (1.0, DVec3::splat(1e9)),
    ] {
        let moved = transformed(&objects, scale, offset);
        let centre = DVec3::splat(0.5) * scale + offset;
        let camera = camera(
            centre + DVec3::new(1.2, 0.9, 2.0) * scale,
            centre,
            45.0,
            48,
            32,
        );
        let context = format!("scale {scale}, offset {offset}");
        check(&moved, &camera, &whole(&camera), everywhere, &context);
    }
}

/// Degenerate triangles (a repeated vertex, three collinear vertices, all
/// three at one point), slivers a millionth wide, one across the whole
/// view, and pairs of coplanar triangles over each other.
#[test]
fn degenerate_sliver_and_coplanar_triangles() {
    let mut rng = Rng::new(21);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut push = |p: [DVec3; 3], positions: &mut Vec<DVec3>| {
        let k = positions.len() as u32;
        positions.extend(p);
        indices.push([k, k + 1, k + 2]);
    };
    for _ in 0..30 {
        let a = rng.point(0.0, 1.0);
        let b = rng.point(0.0, 1.0);
        let c = rng.point(0.0, 1.0);
        push([a, a, b], &mut positions);
        push([a, 0.5 * (a + b), b], &mut positions);
        push([c, c, c], &mut positions);
        let thin = (b - a).cross(DVec3::Y).normalize_or_zero() * 1e-6;
        push([a, b, a + thin], &mut positions);
        push([a, b, c], &mut positions);
        push([a, c, b], &mut positions);
    }
    push(
        [
            DVec3::new(-5.0, 0.5, 0.5),
            DVec3::new(5.0, 0.5, 0.5),
            DVec3::new(5.0, 0.5 + 1e-7, 0.5),
        ],
        &mut positions,
    );
    let objects = [mesh(positions, indices)];
    for (eye, fov) in [
        (DVec3::new(0.4, 1.1, 2.6), 40.0),
        (DVec3::new(0.5, 0.55, 0.45), 90.0),
    ] {
        let camera = camera(eye, DVec3::splat(0.5), fov, 61, 45);
        check(
            &objects,
            &camera,
            &whole(&camera),
            everywhere,
            &format!("eye {eye}"),
        );
    }
}

/// Triangles all around the eye: behind it, beside it, across its plane,
/// through its position.
#[test]
fn triangles_behind_and_across_the_eye_plane() {
    let mut rng = Rng::new(33);
    let eye = DVec3::new(0.1, -0.2, 0.3);
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..40u32 {
        let c = eye + rng.point(-1.5, 1.5);
        for _ in 0..3 {
            positions.push(c + rng.point(-0.8, 0.8));
        }
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    // One through the eye, and one whose edge passes through it.
    let k = positions.len() as u32;
    positions.extend([
        eye - DVec3::X,
        eye + DVec3::new(0.5, 1.0, -1.0),
        eye + DVec3::Z,
    ]);
    indices.push([k, k + 1, k + 2]);
    positions.extend([
        eye - DVec3::Y,
        eye + DVec3::Y,
        eye + DVec3::new(1.0, 0.0, -2.0),
    ]);
    indices.push([k + 3, k + 4, k + 5]);
    let objects = [mesh(positions, indices)];
    for target in [
        eye + DVec3::NEG_Z,
        eye + DVec3::new(1.0, 0.3, 0.2),
        eye + DVec3::Y,
    ] {
        let camera = camera(eye, target, 100.0, 57, 41);
        let (checked, hit) = check(
            &objects,
            &camera,
            &whole(&camera),
            everywhere,
            "around the eye",
        );
        assert!(
            hit > 0 && hit < checked,
            "a mix of hits and misses: {hit} of {checked}"
        );
    }
}

/// A closed UV sphere seen from inside, and a flat grid filling the view:
/// no sample slips between two triangles.
#[test]
fn closed_meshes_are_watertight() {
    let (segments, rings) = (24u32, 13u32);
    let mut positions = vec![DVec3::Y];
    for i in 1..rings {
        let theta = std::f64::consts::PI * f64::from(i) / f64::from(rings);
        for j in 0..segments {
            let phi = std::f64::consts::TAU * f64::from(j) / f64::from(segments);
            positions.push(DVec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ));
        }
    }
    positions.push(DVec3::NEG_Y);
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let last = positions.len() as u32 - 1;
    let mut indices = Vec::new();
    for j in 0..segments {
        indices.push([0, ring(1, j), ring(1, j + 1)]);
        indices.push([last, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            indices.push([a, b, c]);
            indices.push([a, c, d]);
        }
    }
    let sphere = [mesh(positions, indices)];
    for (eye, target) in [
        (DVec3::ZERO, DVec3::new(0.3, 0.1, -1.0)),
        (DVec3::new(0.2, 0.5, -0.1), DVec3::NEG_Y),
        (DVec3::new(0.0, 0.0, 0.0), DVec3::Y),
    ] {
        let camera = camera(eye, target, 120.0, 64, 48);
        let (checked, hit) = check(&sphere, &camera, &whole(&camera), everywhere, "inside");
        assert_eq!(hit, checked, "every sample from inside a closed mesh hits");
    }
    // A grid of 40×40 squares, each cut along a diagonal, in the plane
    // z = 0, seen from in front: every sample of the view hits it.
    let side = 41u32;
    let positions = (0..side * side)
        .map(|k| {
            DVec3::new(
                f64::from(k % side) / 10.0 - 2.0,
                f64::from(k / side) / 10.0 - 2.0,
                0.0,
            )
        })
        .collect();
    let mut indices = Vec::new();
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let at = |i: u32, j: u32| j * side + i;
            indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let grid = [mesh(positions, indices)];
    let camera = camera(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, 50.0, 80, 60);
    let (checked, hit) = check(&grid, &camera, &whole(&camera), everywhere, "grid");
    assert_eq!(hit, checked, "every sample of the grid's view hits it");
}

/// Images of one pixel, one row, one column and 4096×4096 (some of its
/// bins: the corners, the centre and a scatter), and a region of an image.
#[test]
fn tiny_huge_and_cropped_images() {
    let mut rng = Rng::new(57);
    let objects = random_objects(&mut rng, 50);
    let eye = DVec3::new(1.4, 1.3, 2.4);
    for (width, height) in [(1, 1), (1, 300), (300, 1), (2, 3)] {
        let camera = camera(eye, DVec3::splat(0.5), 35.0, width, height);
        check(
            &objects,
            &camera,
            &whole(&camera),
            everywhere,
            &format!("{width}×{height}"),
        );
    }
    let camera = camera(eye, DVec3::splat(0.5), 35.0, 4096, 4096);
    let last = 4096 / BIN - 1;
    let pick = |bx: u32, by: u32| {
        let edge = |b: u32| b == 0 || b == last || b == last / 2;
        (edge(bx) && edge(by)) || (bx * 7 + by * 13).is_multiple_of(1499)
    };
    let (_, hit) = check_at(
        &objects,
        &camera,
        &whole(&camera),
        pick,
        &OFFSETS[..1],
        "4096×4096",
    );
    assert!(hit > 0);
    let camera = camera_of_region();
    let region = Region {
        x: 13,
        y: 7,
        width: 41,
        height: 29,
    };
    check(&objects, &camera, &region, everywhere, "a region");
}

fn camera_of_region() -> Camera {
    camera(DVec3::new(-0.9, 1.6, 2.1), DVec3::splat(0.5), 50.0, 70, 50)
}

/// Whole renders: rasterized and traced, the same bytes, for both shading
/// modes, one and several samples, regions, terms, spheres and planes
/// beside meshes.
#[test]
fn rasterized_renders_are_the_traced_renders() {
    let base = json!({
        "materials": {
            "gold": { "diffuse": [0.75, 0.6, 0.23], "specular": [0.6, 0.55, 0.4], "shininess": 50 },
            "blue": { "diffuse": [0.1, 0.3, 0.8] },
        },
        "light_model": { "two_side": true },
        "lights": [
            { "position": [2, 3, 4, 1], "attenuation": [1, 0.02, 0.005] },
            { "position": [-1, 0.5, 0.3, 0], "diffuse": [0.3, 0.3, 0.45] },
        ],
        "camera": { "eye": [0.3, 1.5, 2.6], "target": [0.5, 0.4, 0.5], "up": [0, 1, 0],
                    "fov_y": 50, "width": 83, "height": 61 },
    });
    let mut rng = Rng::new(77);
    let soup: Vec<[f64; 3]> = (0..120).map(|_| rng.point(0.0, 1.0).to_array()).collect();
    let normals: Vec<[f64; 3]> = (0..120).map(|_| rng.unit_direction().to_array()).collect();
    let indices: Vec<u32> = (0..120).collect();
    let objects = json!([
        { "mesh": { "positions": soup, "normals": normals, "indices": indices }, "material": "gold" },
        { "sphere": { "center": [0.2, 0.3, 0.9], "radius": 0.25 }, "material": "blue" },
        { "plane": { "point": [0, 0, 0], "normal": [0, 1, 0] }, "material": "blue" },
    ]);
    for shading in ["per_vertex", "per_pixel"] {
        for samples in [1, 4] {
            for region in [
                None,
                Some(json!({ "x": 9, "y": 17, "width": 40, "height": 23 })),
            ] {
                let mut request = base.clone();
                request["objects"] = objects.clone();
                request["shading"] = json!(shading);
                request["samples"] = json!(samples);
                if let Some(region) = &region {
                    request["region"] = region.clone();
                }
                let scene = scene_of(&request);
                let raster = Renderer::with_visibility(&scene, Visibility::Rasterized);
                let traced = Renderer::with_visibility(&scene, Visibility::Traced);
                let a = raster.render(true, &|| false).unwrap();
                let b = traced.render(true, &|| false).unwrap();
                let context = format!("{shading}, {samples} samples, region {region:?}");
                assert_eq!((a.width, a.height), (b.width, b.height), "{context}");
                assert!(a.rgba == b.rgba, "{context}: the images differ");
                assert_eq!(
                    format!("{:?}", a.summary),
                    format!("{:?}", b.summary),
                    "{context}: the term summaries differ"
                );
            }
        }
    }
}

/// The decided samples of a frame lit per pixel by an f32 tier, without
/// shadows or terms, every object of one material, are lit straight from
/// their exact tests (`Renderer::light_decided`): the traced frame's
/// bytes, in both f32 tiers, with and without vertex normals, one and two
/// sides lit, linear and sRGB (each combination), the mesh's material not
/// the scene's first.
#[test]
fn decided_samples_lit_straight_are_the_traced_pixels() {
    let mut rng = Rng::new(4127);
    for case in 0..16 {
        let corners = 450;
        let soup: Vec<[f64; 3]> = (0..corners)
            .map(|_| rng.point(-1.0, 1.0).to_array())
            .collect();
        let normals: Vec<[f64; 3]> = (0..corners)
            .map(|_| rng.unit_direction().to_array())
            .collect();
        let mut mesh =
            json!({ "positions": soup, "indices": (0..corners as u32).collect::<Vec<_>>() });
        if case & 1 == 0 {
            mesh["normals"] = json!(normals);
        }
        let two_sided = case & 2 != 0;
        let request = json!({
            "materials": {
                "paint": { "ambient": [0.2, 0.1, 0.05], "diffuse": [0.7, 0.5, 0.6, 0.8],
                           "specular": [0.5, 0.5, 0.5], "shininess": rng.uniform(1.0, 90.0) },
                // First by name, and unused.
                "apricot": { "diffuse": [0.9, 0.4, 0.1] },
            },
            "back_material": { "diffuse": [0.2, 0.8, 0.4] },
            "light_model": { "two_side": two_sided },
            "lights": [
                { "position": [2, 3, 4, 1], "attenuation": [1, 0.05, 0.01] },
                { "position": [-1, 0.5, 0.3, 0], "diffuse": [0.9, 0.8, 1.4] },
            ],
            "camera": { "eye": (rng.unit_direction() * 3.5).to_array(),
                        "target": rng.point(-0.3, 0.3).to_array(), "up": [0, 1, 0],
                        "fov_y": 40, "width": 97, "height": 71 },
            "objects": [{ "mesh": mesh, "material": "paint" }],
            "shading": "per_pixel",
            "encoding": if case & 8 == 0 { "linear" } else { "srgb" },
            "precision": if case & 4 == 0 { "accurate" } else { "fast" },
        });
        let scene = scene_of(&request);
        let render = |visibility| {
            let renderer = Renderer::with_visibility(&scene, visibility);
            renderer.render(false, &|| false).unwrap().rgba
        };
        let (a, b) = (render(Visibility::Rasterized), render(Visibility::Traced));
        let differing = a
            .chunks_exact(4)
            .zip(b.chunks_exact(4))
            .position(|(p, q)| p != q);
        assert!(
            differing.is_none(),
            "case {case}: pixel {differing:?} differs"
        );
    }
}

/// Samples on the pixel grid's corners, the right and bottom edges of a
/// bin included, over a floor of two triangles and a sphere.
#[test]
fn samples_on_pixel_corners_and_bin_edges() {
    let scene = scene_of(&json!({
        "materials": { "blue": {} },
        "camera": { "eye": [0, 1.5, 4], "target": [0, 0.5, 0], "up": [0, 1, 0],
                    "fov_y": 40, "width": 48, "height": 36 },
        "objects": [
            { "sphere": { "center": [0, 0.7, 0], "radius": 0.7 }, "material": "blue" },
            { "mesh": { "positions": [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]],
                        "indices": [0, 2, 1, 0, 3, 2] }, "material": "blue" },
        ],
    }));
    let camera = scene.camera;
    let geometry = Geometry::new(&scene.objects);
    let pinhole = PinholeCamera::new(&camera);
    let region = whole(&camera);
    let raster = Raster::new(&geometry, &scene.objects, &pinhole, &camera, &region).unwrap();
    let mut scratch = RasterScratch::default();
    for by in 0..camera.height.div_ceil(BIN) {
        for bx in 0..camera.width.div_ceil(BIN) {
            let (x0, y0) = (bx * BIN, by * BIN);
            let mut points = Vec::new();
            for y in y0..=(y0 + BIN).min(camera.height) {
                for x in x0..=(x0 + BIN).min(camera.width) {
                    points.push((f64::from(x), f64::from(y)));
                }
            }
            let rays: Vec<Ray> = points.iter().map(|&(x, y)| pinhole.ray(x, y)).collect();
            let mut hits = vec![None; rays.len()];
            raster.hits(&geometry, (x0, y0), &points, &rays, &mut hits, &mut scratch);
            for ((point, ray), found) in points.iter().zip(&rays).zip(&hits) {
                let brute = geometry.closest_hit_brute_force(ray);
                same(*found, brute, &format!("corner {point:?}"));
            }
        }
    }
}

/// One Gouraud-shaded sample per pixel, the meshes' only shapes and linear
/// encoding: the rasterized render computes the bytes of the pixels it
/// decides from the edge functions, without tracing them
/// (`raster_gouraud`); the image is still the traced image, byte for byte.
/// Random soups whose triangles cross each other and the eye's plane, eyes
/// outside and inside the box, one and two sides lit, normals per vertex
/// and per face, the three tiers, regions; Gouraud shading (its bytes from
/// the rasterizer's decisions, with linear encoding) and per-pixel
/// lighting (the decided samples' exact test on their triangle alone),
/// with linear and sRGB encoding, with and without shadows and the terms,
/// under a spotlight whose cone's edge crosses the soup.
#[test]
fn one_sample_per_pixel_is_the_traced_pixel() {
    let mut rng = Rng::new(2911);
    let mut decided_pixels = 0usize;
    for case in 0..24 {
        let count = 60 + 40 * (case % 4);
        let soup: Vec<[f64; 3]> = (0..3 * count)
            .map(|_| rng.point(-1.0, 1.0).to_array())
            .collect();
        let normals: Vec<[f64; 3]> = (0..3 * count)
            .map(|_| rng.unit_direction().to_array())
            .collect();
        let indices: Vec<u32> = (0..3 * count as u32).collect();
        let mut mesh = json!({ "positions": soup, "indices": indices });
        if case % 2 == 0 {
            mesh["normals"] = json!(normals);
        }
        // Outside the box, at its edge, and inside it.
        let eye = match case % 3 {
            0 => rng.unit_direction() * 3.5,
            1 => rng.unit_direction() * 1.2,
            _ => rng.point(-0.5, 0.5),
        };
        let target = rng.point(-0.3, 0.3);
        let precision = ["reference", "accurate", "fast"][case % 3];
        let mut request = json!({
            "materials": {
                "paint": { "ambient": [0.2, 0.1, 0.05], "diffuse": [rng.uniform(0.2, 1.0), rng.uniform(0.2, 1.0), 0.6, rng.uniform(0.3, 1.0)],
                           "specular": [0.5, 0.5, 0.5], "shininess": rng.uniform(1.0, 90.0) },
            },
            "light_model": { "two_side": case % 4 < 2, "local_viewer": true },
            "lights": [
                { "position": [2, 3, 4, 1], "attenuation": [1, 0.05, 0.01] },
                { "position": [-1, 0.5, 0.3, 0], "diffuse": [0.9, 0.8, 1.4] },
                // A cone whose edge crosses the soup: blocks of vertices
                // across it take the kernel's exact test of the cone.
                { "position": [0.2, 2.5, 0.4, 1],
                  "spot": { "direction": [-0.1, -1, 0], "exponent": 6, "cutoff": 25 } },
            ],
            "camera": { "eye": eye.to_array(), "target": target.to_array(), "up": [0, 1, 0],
                        "fov_y": rng.uniform(30.0, 90.0), "width": 97, "height": 71 },
            "objects": [{ "mesh": mesh, "material": "paint" }],
            "shading": if case < 12 { "per_vertex" } else { "per_pixel" },
            "encoding": if case % 6 == 5 { "srgb" } else { "linear" },
            "shadows": case % 7 == 6,
            "precision": precision,
            "background": [0.1, 0.2, 0.3, 1.0],
        });
        if case % 5 == 4 {
            request["region"] = json!({ "x": 11, "y": 20, "width": 50, "height": 33 });
        }
        let with_terms = case % 4 == 3;
        let scene = scene_of(&request);
        let raster = Renderer::with_visibility(&scene, Visibility::Rasterized);
        let traced = Renderer::with_visibility(&scene, Visibility::Traced);
        let a = raster.render(with_terms, &|| false).unwrap();
        let b = traced.render(with_terms, &|| false).unwrap();
        assert_eq!(a.sampling, b.sampling, "case {case}");
        assert_eq!(
            format!("{:?}", a.summary),
            format!("{:?}", b.summary),
            "case {case}: the term summaries differ"
        );
        assert_eq!(
            raster.rays(),
            traced.rays(),
            "case {case}: each pixel's centre ray counts"
        );
        let differing = a
            .rgba
            .chunks_exact(4)
            .zip(b.rgba.chunks_exact(4))
            .position(|(p, q)| p != q);
        assert!(
            differing.is_none(),
            "case {case}: pixel {differing:?} differs"
        );
        // The background's bytes: round(255·c), on sRGB's curve (IEC
        // 61966-2-1) when asked for.
        let srgb = |c: f64| 1.055 * c.powf(1.0 / 2.4) - 0.055;
        let background = [0.1, 0.2, 0.3].map(|c: f64| {
            let encoded = if case % 6 == 5 { srgb(c) } else { c };
            (255.0 * encoded).round() as u8
        });
        decided_pixels += a
            .rgba
            .chunks_exact(4)
            .filter(|p| p[..3] != background)
            .count();
    }
    assert!(
        decided_pixels > 40_000,
        "the meshes cover the images: {decided_pixels} pixels"
    );
}
