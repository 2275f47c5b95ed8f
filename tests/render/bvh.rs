//! The BVH against brute force: over random rays and random meshes (and
//! spheres and a plane), the closest hit through the BVH is the one found by
//! testing every primitive, exactly, at any scale and offset of the scene;
//! so is the shadow query. Both trees answer: the CWBVH of frames whose
//! primary rays are traced and the LBVH of frames whose primary rays are
//! rasterized.

use glam::DVec3;
use glint_trace::bvh::BvhUse;
use glint_trace::geometry::{Geometry, Hit, Ray, SPHERES_TESTED_ALL};
use glint_trace::packet::Packets;
use glint_trace::{Mesh, Object, Plane, Shape, Sphere};

use crate::support::Rng;

/// The points and directions of these scenes, drawn from the shared seeded
/// [`Rng`].
impl Rng {
    pub(super) fn point(&mut self, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(
            self.uniform(lo, hi),
            self.uniform(lo, hi),
            self.uniform(lo, hi),
        )
    }

    pub(super) fn unit_direction(&mut self) -> DVec3 {
        loop {
            let v = self.point(-1.0, 1.0);
            if v.length_squared() > 1e-6 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

/// A soup of `n` random triangles in the unit cube, of assorted sizes, and
/// a connected grid surface through it.
pub(super) fn random_objects(rng: &mut Rng, n: usize) -> Vec<Object> {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n {
        let size = if i % 10 == 0 { 0.5 } else { 0.05 };
        let c = rng.point(0.0, 1.0);
        for _ in 0..3 {
            positions.push(c + size * rng.point(-1.0, 1.0));
        }
        let k = 3 * i as u32;
        indices.push([k, k + 1, k + 2]);
    }
    let soup = Mesh {
        positions,
        normals: None,
        indices,
    };
    // A 20×20 height field: shared edges and vertices.
    let side = 21u32;
    let grid_positions = (0..side * side)
        .map(|k| {
            let (i, j) = ((k % side) as f64 / 20.0, (k / side) as f64 / 20.0);
            DVec3::new(i, 0.5 + 0.2 * (7.0 * i).sin() * (5.0 * j).cos(), j)
        })
        .collect();
    let mut grid_indices = Vec::new();
    for j in 0..side - 1 {
        for i in 0..side - 1 {
            let at = |i: u32, j: u32| j * side + i;
            grid_indices.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
            grid_indices.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    let grid = Mesh {
        positions: grid_positions,
        normals: None,
        indices: grid_indices,
    };
    let mut objects = vec![
        Object {
            shape: Shape::Mesh(soup),
            material: 0,
        },
        Object {
            shape: Shape::Mesh(grid),
            material: 0,
        },
    ];
    objects.extend((0..8).map(|_| random_sphere(rng)));
    objects.push(tilted_floor());
    objects
}

/// A sphere in the unit cube, of a radius from 0.01 to 0.15.
fn random_sphere(rng: &mut Rng) -> Object {
    Object {
        shape: Shape::Sphere(Sphere {
            center: rng.point(0.0, 1.0),
            radius: rng.uniform(0.01, 0.15),
        }),
        material: 0,
    }
}

/// A plane under the unit cube, tilted off the axes.
fn tilted_floor() -> Object {
    Object {
        shape: Shape::Plane(Plane {
            point: DVec3::new(0.0, -0.2, 0.0),
            normal: DVec3::new(0.1, 1.0, 0.05).normalize(),
        }),
        material: 0,
    }
}

/// `objects` scaled by `scale` about the origin, then moved by `offset`.
pub(super) fn transformed(objects: &[Object], scale: f64, offset: DVec3) -> Vec<Object> {
    let map = |p: DVec3| p * scale + offset;
    objects
        .iter()
        .map(|o| Object {
            shape: match &o.shape {
                Shape::Mesh(m) => Shape::Mesh(Mesh {
                    positions: m.positions.iter().map(|&p| map(p)).collect(),
                    normals: m.normals.clone(),
                    indices: m.indices.clone(),
                }),
                Shape::Sphere(s) => Shape::Sphere(Sphere {
                    center: map(s.center),
                    radius: s.radius * scale,
                }),
                Shape::Plane(p) => Shape::Plane(Plane {
                    point: map(p.point),
                    normal: p.normal,
                }),
            },
            material: o.material,
        })
        .collect()
}

/// Points on the objects (triangle centroids and sphere centres), to aim
/// rays at.
fn aim_points(objects: &[Object]) -> Vec<DVec3> {
    let mut out = Vec::new();
    for o in objects {
        match &o.shape {
            Shape::Mesh(m) => out.extend(
                m.indices
                    .iter()
                    .map(|t| t.iter().map(|&i| m.positions[i as usize]).sum::<DVec3>() / 3.0),
            ),
            Shape::Sphere(s) => out.push(s.center),
            Shape::Plane(_) => {}
        }
    }
    out
}

#[track_caller]
pub(super) fn same(bvh: Option<Hit>, brute: Option<Hit>, context: &str) {
    match (bvh, brute) {
        (None, None) => {}
        (Some(a), Some(b)) => assert_eq!(a, b, "{context}"),
        _ => panic!("{context}: the BVH found {bvh:?}, brute force {brute:?}"),
    }
}

/// Traces `rays` in packets and checks every hit against brute force;
/// returns the hits.
fn packet_hits(
    packets: &Packets,
    geometry: &Geometry,
    rays: &[Ray],
    context: &str,
) -> Vec<Option<Hit>> {
    let mut hits = vec![None; rays.len()];
    packets.trace(geometry, rays, &mut hits);
    for (k, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
        let context = format!("{context}: ray {k} {ray:?}");
        same(*hit, geometry.closest_hit_brute_force(ray), &context);
    }
    hits
}

/// Both trees: the CWBVH of traced frames and the LBVH of frames whose
/// primary rays are rasterized.
fn geometries(objects: &[Object]) -> [(BvhUse, Geometry); 2] {
    [BvhUse::PrimaryRays, BvhUse::ShadowRays].map(|usage| {
        let geometry = Geometry::new(objects);
        geometry.build_bvh(usage);
        (usage, geometry)
    })
}

fn check_scene(objects: &[Object], scale: f64, offset: DVec3, seed: u64) -> usize {
    let geometries = geometries(objects);
    let targets = aim_points(objects);
    let mut rng = Rng::new(seed);
    let mut hits = 0;
    for k in 0..3000 {
        let ray = match k % 3 {
            // From anywhere around the scene, in any direction.
            0 => Ray::new(rng.point(-0.5, 1.5) * scale + offset, rng.unit_direction()),
            // From outside, at a primitive.
            1 => {
                let target = targets[rng.below(targets.len())];
                let origin = rng.point(-2.0, 3.0) * scale + offset;
                Ray::new(origin, target - origin)
            }
            // From inside, at a primitive, with a limited reach.
            _ => {
                let target = targets[rng.below(targets.len())];
                let origin = rng.point(0.0, 1.0) * scale + offset;
                Ray {
                    t_min: rng.uniform(0.0, 0.1) * scale,
                    t_max: rng.uniform(0.05, 2.0) * scale,
                    ..Ray::new(origin, target - origin)
                }
            }
        };
        if ray.direction.is_nan() {
            continue;
        }
        let brute = geometries[0].1.closest_hit_brute_force(&ray);
        for (usage, geometry) in &geometries {
            let context = format!("{usage:?}: ray {k} {ray:?} (scale {scale}, offset {offset})");
            same(geometry.closest_hit(&ray), brute, &context);
            assert_eq!(
                geometry.occluded(&ray),
                brute.is_some(),
                "{context}: shadow query"
            );
        }
        hits += usize::from(brute.is_some());
    }
    hits
}

#[test]
fn bvh_hits_equal_brute_force_hits() {
    let mut rng = Rng::new(7);
    let objects = random_objects(&mut rng, 2000);
    let hits = check_scene(&objects, 1.0, DVec3::ZERO, 11);
    assert!(hits > 1500, "only {hits} of 3000 rays hit something");
}

/// The BVH works in f32 in a normalised space: tiny, huge and far-off
/// scenes find the same hits as brute force in f64.
#[test]
fn bvh_hits_equal_brute_force_hits_at_any_scale_and_offset() {
    let mut rng = Rng::new(8);
    let objects = random_objects(&mut rng, 500);
    for (scale, offset) in [
        (1e-6, DVec3::ZERO),
        (1e6, DVec3::ZERO),
        (1e-3, DVec3::new(1e5, -2e5, 3e4)),
        (1.0, DVec3::new(-1e9, 0.0, 1e9)),
        (1e20, DVec3::new(1e25, 1e25, -1e25)),
    ] {
        let moved = transformed(&objects, scale, offset);
        let hits = check_scene(&moved, scale, offset, 12);
        assert!(
            hits > 1000,
            "scale {scale}, offset {offset}: only {hits} hits"
        );
    }
}

/// Rays from far away (up to 1e29 off a scene of size 1) find what brute
/// force finds: through the BVH up to about 1e9 scene sizes, beyond that
/// (where the hit points are rounding noise) by testing every primitive.
#[test]
fn bvh_rays_from_far_away_equal_brute_force() {
    let mut rng = Rng::new(9);
    let objects = random_objects(&mut rng, 300);
    let geometries = geometries(&objects);
    let targets = aim_points(&objects);
    for distance in [1e3, 1e6, 1e8, 1e29] {
        let mut hits = 0;
        for (k, &target) in targets.iter().enumerate().take(500) {
            let origin = rng.unit_direction() * distance;
            let ray = Ray::new(origin, target - origin);
            let brute = geometries[0].1.closest_hit_brute_force(&ray);
            for (usage, geometry) in &geometries {
                same(
                    geometry.closest_hit(&ray),
                    brute,
                    &format!("{usage:?}: ray {k} from {distance}"),
                );
                assert_eq!(
                    geometry.occluded(&ray),
                    brute.is_some(),
                    "{usage:?}: ray {k} from {distance}: shadow query"
                );
            }
            hits += usize::from(brute.is_some());
        }
        assert!(hits > 400, "{hits} hits from {distance}");
    }
}

/// Scenes of spheres alone (and a plane), up to and past
/// `SPHERES_TESTED_ALL`, whose shadow rays test every sphere rather than
/// traverse: the shadow query is brute force's, for random rays at any scale
/// and for rays that only touch one sphere, where the test's `disc` is
/// exactly zero.
#[test]
fn shadow_rays_among_few_spheres_equal_brute_force() {
    let mut rng = Rng::new(31);
    for count in [1, 9, 40, SPHERES_TESTED_ALL, SPHERES_TESTED_ALL + 1] {
        let mut objects: Vec<Object> = (0..count).map(|_| random_sphere(&mut rng)).collect();
        objects.push(tilted_floor());
        for (scale, offset) in [
            (1.0, DVec3::ZERO),
            (1e-3, DVec3::splat(7.0)),
            (1e4, DVec3::ZERO),
        ] {
            let moved = transformed(&objects, scale, offset);
            let hits = check_scene(&moved, scale, offset, 40 + count as u64);
            assert!(
                hits > 200,
                "{count} spheres, scale {scale}: only {hits} hits"
            );
        }

        // Sphere `i` of radius 2^-k at (4i, 8, 0), met by a ray along +x at
        // the height of its lowest point: `f = (−1.5, −r, 0)`, `b = 1.5`,
        // `l = (0, −r, 0)`, so `disc = r² − r² = 0` and the ray touches it at
        // `t = 1.5`, within its reach of 2, which no other sphere enters.
        let radius = |i: usize| 0.5f64.powi((i % 4) as i32);
        let spheres: Vec<Object> = (0..count)
            .map(|i| Object {
                shape: Shape::Sphere(Sphere {
                    center: DVec3::new(4.0 * i as f64, 8.0, 0.0),
                    radius: radius(i),
                }),
                material: 0,
            })
            .collect();
        for (usage, geometry) in geometries(&spheres) {
            for i in 0..count {
                let ray = Ray {
                    t_max: 2.0,
                    ..Ray::new(
                        DVec3::new(4.0 * i as f64 - 1.5, 8.0 - radius(i), 0.0),
                        DVec3::X,
                    )
                };
                let brute = geometry.closest_hit_brute_force(&ray);
                assert_eq!(
                    brute.map(|h| (h.object, h.t)),
                    Some((i as u32, 1.5)),
                    "{usage:?}: the ray touches sphere {i} of {count}"
                );
                assert!(
                    geometry.occluded(&ray),
                    "{usage:?}: sphere {i} of {count} shadows"
                );
                let beyond = Ray { t_max: 1.25, ..ray };
                assert!(
                    !geometry.occluded(&beyond),
                    "{usage:?}: sphere {i} of {count} out of reach"
                );
            }
        }
    }
}

#[test]
fn scenes_with_one_primitive_or_none() {
    let sphere = Object {
        shape: Shape::Sphere(Sphere {
            center: DVec3::new(0.0, 0.0, -5.0),
            radius: 1.0,
        }),
        material: 0,
    };
    let one = Geometry::new(std::slice::from_ref(&sphere));
    let hit = one
        .closest_hit(&Ray::new(DVec3::ZERO, DVec3::NEG_Z))
        .expect("the ray hits the sphere");
    assert_eq!((hit.object, hit.t), (0, 4.0));
    assert!(one.closest_hit(&Ray::new(DVec3::ZERO, DVec3::Z)).is_none());

    let none = Geometry::new(&[]);
    assert!(
        none.closest_hit(&Ray::new(DVec3::ZERO, DVec3::NEG_Z))
            .is_none()
    );
    assert!(!none.occluded(&Ray::new(DVec3::ZERO, DVec3::NEG_Z)));
    assert_eq!(none.triangles(), 0);
}

/// Rays aimed from `eye` at the objects: at triangle centroids and
/// vertices, at the midpoints of the grid's shared edges, at sphere
/// centres and rims, nudged by up to `jitter` (relative to the scene), and
/// in random directions.
fn rays_from(eye: DVec3, objects: &[Object], rng: &mut Rng, n: usize, jitter: f64) -> Vec<Ray> {
    let mut targets = aim_points(objects);
    for o in objects {
        match &o.shape {
            Shape::Mesh(m) => {
                targets.extend(m.positions.iter().copied());
                targets.extend(m.indices.iter().flat_map(|&[a, b, c]| {
                    let [a, b, c] = [a, b, c].map(|i| m.positions[i as usize]);
                    [(a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0]
                }));
            }
            Shape::Sphere(s) => {
                targets.push(s.center + s.radius * rng.unit_direction());
            }
            Shape::Plane(_) => {}
        }
    }
    let scale = objects_scale(objects);
    (0..n)
        .map(|k| {
            if k % 5 == 4 {
                return Ray::new(eye, rng.unit_direction());
            }
            let target = targets[rng.below(targets.len())];
            let nudge = match k % 3 {
                0 => DVec3::ZERO,
                1 => rng.point(-1.0, 1.0) * jitter * scale,
                _ => rng.point(-1.0, 1.0) * 1e-12 * scale,
            };
            Ray::new(eye, target + nudge - eye)
        })
        .filter(|ray| !ray.direction.is_nan())
        .collect()
}

/// The size of the scene: its largest bounded extent.
fn objects_scale(objects: &[Object]) -> f64 {
    let points: Vec<DVec3> = aim_points(objects);
    let lo = points.iter().fold(DVec3::INFINITY, |a, &b| a.min(b));
    let hi = points.iter().fold(DVec3::NEG_INFINITY, |a, &b| a.max(b));
    (hi - lo).max_element()
}

/// The packets of primary rays find, ray for ray, exactly the hit brute
/// force finds (object, triangle, t, barycentrics), from eyes inside and
/// around scenes of any scale and offset, including rays through shared
/// vertices and edges and rays grazing them.
#[test]
fn packet_hits_equal_brute_force_hits() {
    let mut rng = Rng::new(21);
    let objects = random_objects(&mut rng, 400);
    let mut traced = 0;
    for (scale, offset) in [
        (1.0, DVec3::ZERO),
        (1e-6, DVec3::ZERO),
        (1e6, DVec3::new(-3e6, 1e6, 0.0)),
        (1e-3, DVec3::new(1e5, -2e5, 3e4)),
        (1.0, DVec3::new(-1e9, 0.0, 1e9)),
    ] {
        let moved = transformed(&objects, scale, offset);
        let geometry = Geometry::new(&moved);
        for e in 0..12 {
            // Inside the scene, around it, and up to three scene sizes off.
            let spread = [0.2, 1.0, 3.0][e % 3];
            let eye = (rng.point(-spread, 1.0 + spread)) * scale + offset;
            let Some(packets) = Packets::new(&geometry, eye) else {
                panic!("no packets for an eye at {eye} (scale {scale}, offset {offset})");
            };
            let rays = rays_from(eye, &moved, &mut rng, 400, 1e-6);
            let context = format!("scale {scale}, offset {offset}");
            let hits = packet_hits(&packets, &geometry, &rays, &context);
            for (ray, hit) in rays.iter().zip(&hits) {
                same(
                    *hit,
                    geometry.closest_hit(ray),
                    &format!("{context}: {ray:?}"),
                );
            }
            traced += rays.len();
        }
    }
    assert!(traced > 20_000, "{traced} rays");
}

/// No cracks: a ray from above through a vertex or an edge shared by
/// triangles of a height field hits one of them. (From above: every ray is
/// steeper than the field's slopes, up to 1.72, so no shared edge is a
/// silhouette, which a ray may graze past in exact arithmetic too.)
#[test]
fn packet_rays_through_shared_edges_and_vertices_hit() {
    let mut rng = Rng::new(22);
    let objects = random_objects(&mut rng, 0);
    let Shape::Mesh(grid) = &objects[1].shape else {
        panic!("the second object is the grid")
    };
    let geometry = Geometry::new(&objects[1..2]);
    let mut points: Vec<DVec3> = grid.positions.clone();
    for &[a, b, c] in &grid.indices {
        let [a, b, c] = [a, b, c].map(|i| grid.positions[i as usize]);
        points.extend([(a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0]);
    }
    // Inside the grid's square only: its border edges have one triangle.
    points.retain(|p| p.x > 0.0 && p.x < 1.0 && p.z > 0.0 && p.z < 1.0);
    for eye in [DVec3::new(0.5, 2.0, 0.5), DVec3::new(0.3, 3.0, 0.6)] {
        let packets = Packets::new(&geometry, eye).expect("packets for a near eye");
        let rays: Vec<Ray> = points.iter().map(|&p| Ray::new(eye, p - eye)).collect();
        let hits = packet_hits(&packets, &geometry, &rays, "through a shared edge");
        for (ray, hit) in rays.iter().zip(&hits) {
            assert!(hit.is_some(), "a crack: {ray:?} from {eye} hits nothing");
        }
    }
}

/// The planes of a packet are those of brute force: the nearer of two,
/// the first of two at the same place, none for a ray parallel to a plane
/// (from below the ceiling, `offset / 0` is +∞, which must not count as a
/// hit) or leaving it behind, and a plane nearer than the mesh beyond it.
#[test]
fn packet_planes_are_the_brute_force_planes() {
    let plane = |point: DVec3, normal: DVec3| Object {
        shape: Shape::Plane(Plane { point, normal }),
        material: 0,
    };
    let floor = plane(DVec3::ZERO, DVec3::Y);
    let mut rng = Rng::new(24);
    let mut objects = random_objects(&mut rng, 50);
    objects.extend([
        floor.clone(),
        floor,
        plane(DVec3::new(2.0, 0.0, 0.0), DVec3::new(-1.0, 0.2, 0.0)),
        plane(DVec3::new(0.0, 0.0, -3.0), DVec3::Z),
        plane(DVec3::new(0.0, 3.0, 0.0), DVec3::Y),
    ]);
    let geometry = Geometry::new(&objects);
    let eye = DVec3::new(0.5, 1.5, 1.5);
    let packets = Packets::new(&geometry, eye).expect("packets for a near eye");
    let mut rays = rays_from(eye, &objects, &mut rng, 160, 1e-3);
    // Parallel to the floor and the ceiling (their denominators exactly 0),
    // up to the ceiling, and straight down onto the floor.
    for k in 0..48 {
        let angle = f64::from(k) * 0.13;
        let direction = match k % 3 {
            0 => DVec3::new(angle.cos(), 0.0, angle.sin()),
            1 => DVec3::new(angle.cos(), 0.5, angle.sin()),
            _ => DVec3::new(0.01 * angle.cos(), -1.0, 0.01 * angle.sin()),
        };
        rays.push(Ray::new(eye, direction));
    }
    let hits = packet_hits(&packets, &geometry, &rays, "planes");
    let planes = hits.iter().flatten().filter(|hit| hit.object >= 10).count();
    assert!(planes > 40, "{planes} plane hits");
    assert!(
        hits.iter().flatten().all(|hit| hit.object != 12),
        "the second of two equal planes is never the closest"
    );
}

/// Packets decline an eye too far from the scene (the renderer then traces
/// its rays one by one), and trace alone any ray not from their eye.
#[test]
fn packets_decline_far_eyes_and_foreign_rays() {
    let mut rng = Rng::new(23);
    let objects = random_objects(&mut rng, 200);
    let geometry = Geometry::new(&objects);
    assert!(Packets::new(&geometry, DVec3::splat(1e4)).is_none());
    let eye = DVec3::new(0.5, 1.5, -1.0);
    let packets = Packets::new(&geometry, eye).expect("packets for a near eye");
    let mut rays = rays_from(eye, &objects, &mut rng, 64, 1e-3);
    rays[3].origin += DVec3::splat(1e-3);
    rays[7].t_max = 0.5;
    rays[9].t_min = 0.1;
    packet_hits(&packets, &geometry, &rays, "a mixed packet");
}
