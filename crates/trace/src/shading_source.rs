//! How a [`Renderer`] made the colour of any pixel, told to the diagnosis
//! of an image compare ([`glint_compare::image::ShadingSource`]): each
//! pixel the mean of its samples, each sample either the background or the
//! colour of the surface its primary ray hit, so that a pixel is a weighted
//! sum of shading points' colours and a constant.
//!
//! A sample lit per pixel is one shading point (the hit, its interpolated
//! normal, its material and lit side, the lights its shadow rays reach),
//! of weight `1/n` for `n` samples. A sample on a mesh shaded per vertex
//! (Gouraud) is the mesh's vertex colours interpolated by the hit's
//! barycentrics: three shading points (the triangle's vertices, or its
//! corners where the mesh has no normals) of weights `(1 − u − v)/n`,
//! `u/n` and `v/n`. A miss adds `background/n` to the constant.
//!
//! The samples are the renderer's own: the same offsets in the pixel
//! ([`crate::film::SamplePattern`]), the same primary rays
//! ([`crate::camera::PinholeCamera::ray`], bit for bit those of the
//! frame), the same exact closest hits (found here through the BVH, which
//! finds the hits the rasterizer finds), the same shadow rays. So the
//! composition of GL's colours at the points is GL's pixel before its
//! 8-bit rounding, and a deviation evaluated at the points is the pixel a
//! port with that deviation draws.
//!
//! Adaptive sampling decides how many samples a pixel takes from the
//! colours it finds; a port's colours would take others. Its pixels are
//! not a fixed sum of shading points, and [`Renderer::shading_source`]
//! declines it.

use std::collections::HashMap;

use glam::{DVec3, Vec4};
use glint_compare::image::{ImageScene, PixelShading, ShadingPoint, ShadingSource};
use glint_lighting::reference::Port;
use glint_lighting::{LightMask, Side, Viewer, bounding_box_centre, unit_or_zero};

use crate::bvh::BvhUse;
use crate::geometry::{Hit, Ray};
use crate::hit_lighting::Facing;
use crate::scene::{Samples, Shape};
use crate::{Renderer, ShadingMode};

/// A renderer's pixels as sums of shading points: see the module's doc.
pub struct RenderShading<'r, 's> {
    renderer: &'r Renderer<'s>,
    /// Samples in every pixel.
    samples: u32,
}

/// A renderer whose pixels are not a fixed sum of shading points: its
/// sampling is adaptive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdaptiveSampling;

impl<'s> Renderer<'s> {
    /// How this renderer shades its pixels, for
    /// [`glint_compare::image::diagnose_image`]; builds the BVH its rays
    /// need. Declines adaptive sampling (see the module's doc).
    pub fn shading_source(&self) -> Result<RenderShading<'_, 's>, AdaptiveSampling> {
        let Samples::Uniform(samples) = self.scene.samples.effective() else {
            return Err(AdaptiveSampling);
        };
        // The queries run inside rayon tasks: the BVH must exist before.
        self.geometry.build_bvh(match self.raster {
            Some(_) => BvhUse::ShadowRays,
            None => BvhUse::PrimaryRays,
        });
        Ok(RenderShading {
            renderer: self,
            samples,
        })
    }

    /// What lights this renderer's image, for an image compare: the light
    /// set and the materials, the viewer a port with `viewer_swapped` uses
    /// (the eye for GL's infinite viewer, the direction towards the eye for
    /// a local one), the centre on which the renderer's kernels recentre,
    /// and whether some normal reaching the lighting is not of unit length.
    pub fn image_scene(&self) -> ImageScene<'_> {
        let scene = self.scene;
        let camera = &scene.camera;
        let local = matches!(scene.lights.viewer, Viewer::Local(_));
        let towards_eye = unit_or_zero(camera.eye - camera.target);
        let bounds = self.geometry.bounds();
        let extent = if bounds.min.x <= bounds.max.x {
            vec![bounds.min, bounds.max, camera.eye]
        } else {
            vec![camera.eye]
        };
        let unnormalized_normals = scene.objects.iter().any(|o| match &o.shape {
            // Normals interpolated across a triangle are shorter than its
            // vertices' (per pixel); per vertex the mesh's own reach the
            // lighting.
            Shape::Mesh(mesh) => mesh.normals.as_ref().is_some_and(|normals| {
                scene.shading == ShadingMode::PerPixel
                    || glint_compare::image::has_unnormalized(normals)
            }),
            _ => false,
        });
        ImageScene {
            lights: &scene.lights,
            materials: &scene.materials,
            precision: scene.precision,
            swapped_viewer: Port::swapped_viewer(local, camera.eye, towards_eye),
            centre: bounding_box_centre(&extent),
            unnormalized_normals,
        }
    }
}

/// A Gouraud shading point's identity: object, vertex (or corner), and
/// whether it is lit on its back.
type VertexKey = (u32, usize, bool);

impl ShadingSource for RenderShading<'_, '_> {
    fn shading(&self, pixels: &[u32], out: &mut PixelShading) {
        let renderer = self.renderer;
        let region = renderer.scene.region;
        let weight = 1.0 / self.samples as f32;
        let background = renderer.scene.background.as_vec4() * weight;
        // A vertex shared by the pixels of this run is one point.
        let mut vertices: HashMap<VertexKey, u32> = HashMap::new();
        for &pixel in pixels {
            let x = region.x + pixel % region.width;
            let y = region.y + pixel / region.width;
            let start = out.terms.len() as u32;
            let mut constant = Vec4::ZERO;
            for k in 0..self.samples {
                let (ox, oy) = renderer.pattern.offset(x, y, k);
                let ray = renderer.camera.ray(f64::from(x) + ox, f64::from(y) + oy);
                match renderer.geometry.closest_hit(&ray) {
                    None => constant += background,
                    Some(hit) if renderer.vertex_colors[hit.object as usize].is_some() => {
                        self.gouraud(&ray, hit, weight, &mut vertices, out)
                    }
                    Some(hit) => {
                        let s = renderer.surface(&ray, hit);
                        let side = renderer.lit_side(s.side);
                        let facing = match side {
                            Side::Front => s.normal,
                            Side::Back => -s.normal,
                        };
                        let visible = self.visible(s.point, s.geometric, Facing::One(facing));
                        out.terms.push((out.points.len() as u32, weight));
                        out.points.push(ShadingPoint {
                            position: s.point,
                            normal: s.normal,
                            material: renderer.scene.objects[s.object].material as u32,
                            side,
                            visible,
                        });
                    }
                }
            }
            out.pixels.push(start..out.terms.len() as u32);
            out.constant.push(constant);
        }
    }
}

impl RenderShading<'_, '_> {
    /// The terms of a sample on a mesh lit at its vertices: its triangle's
    /// vertices (or corners) with their barycentric weights, as
    /// `VertexColors::interpolate` weighs their colours.
    fn gouraud(
        &self,
        ray: &Ray,
        hit: Hit,
        weight: f32,
        vertices: &mut HashMap<VertexKey, u32>,
        out: &mut PixelShading,
    ) {
        let renderer = self.renderer;
        let object = &renderer.scene.objects[hit.object as usize];
        let Shape::Mesh(mesh) = &object.shape else {
            unreachable!("vertex colours belong to meshes")
        };
        let triangle = hit.triangle as usize;
        let geometric = renderer.face_normal(hit.object as usize, triangle);
        let side = renderer.lit_side(if geometric.dot(ray.direction) > 0.0 {
            Side::Back
        } else {
            Side::Front
        });
        let indices = mesh.indices[triangle].map(|i| i as usize);
        let barycentric = [1.0 - hit.u - hit.v, hit.u, hit.v];
        for (corner, (&index, &b)) in indices.iter().zip(&barycentric).enumerate() {
            // Without normals a mesh is lit per corner, with its face's
            // normal (see `VertexColors::new`).
            let (key, normal) = match &mesh.normals {
                Some(normals) => (index, normals[index]),
                None => (3 * triangle + corner, geometric),
            };
            let point = *vertices
                .entry((hit.object, key, side == Side::Back))
                .or_insert_with(|| {
                    let position = mesh.positions[index];
                    let facing = match renderer.two_side {
                        true => Facing::Both(normal),
                        false => Facing::One(normal),
                    };
                    out.points.push(ShadingPoint {
                        position,
                        normal,
                        material: object.material as u32,
                        side,
                        visible: self.visible(position, unit_or_zero(normal), facing),
                    });
                    out.points.len() as u32 - 1
                });
            out.terms.push((point, weight * b as f32));
        }
    }

    /// The lights that reach `point`: every one without shadows, else the
    /// renderer's own shadow rays.
    fn visible(&self, point: DVec3, geometric: DVec3, facing: Facing) -> LightMask {
        let renderer = self.renderer;
        if !renderer.scene.shadows {
            return LightMask::MAX;
        }
        let mut rays = 0;
        renderer.visibility(point, geometric, facing, &mut rays)
    }
}

#[cfg(test)]
mod tests {
    use glam::{DVec3, DVec4};
    use glint_compare::image::{PixelShading, ShadingPoint, ShadingSource};
    use glint_lighting::{
        Light, LightModel, LightPosition, LightSet, Material, Precision, SurfaceMaterial, Viewer,
        reference,
    };

    use crate::film;
    use crate::{
        Camera, Encoding, Mesh, Object, Plane, Region, RenderScene, Renderer, Samples, ShadingMode,
        Shape, Sphere,
    };

    /// A sphere, a floor, and a mesh of two triangles, one facing the eye
    /// and one facing away, with normals of other lengths than 1; two
    /// lights, one at a point; two-sided, with shadows, four samples a
    /// pixel, at the reference precision.
    fn scene(shading: ShadingMode, region: Option<Region>) -> RenderScene {
        let camera = Camera {
            eye: DVec3::new(0.0, 1.0, 6.0),
            target: DVec3::new(0.0, 0.5, 0.0),
            up: DVec3::Y,
            fov_y: 40.0,
            width: 48,
            height: 36,
        };
        let model = LightModel {
            two_side: true,
            ..LightModel::default()
        };
        let lights = vec![
            Light {
                position: LightPosition::Directional(DVec3::new(0.4, 1.0, 0.7).normalize()),
                ..Light::default()
            },
            Light {
                position: LightPosition::Positional(DVec3::new(-2.0, 2.5, 2.0)),
                diffuse: DVec4::new(0.5, 0.4, 0.3, 1.0),
                attenuation: [1.0, 0.1, 0.02],
                ..Light::default()
            },
        ];
        let viewer = Viewer::Infinite((camera.eye - camera.target).normalize());
        let material = |r, g, b| Material {
            diffuse: DVec4::new(r, g, b, 1.0),
            specular: DVec4::new(0.6, 0.6, 0.6, 1.0),
            shininess: 16.0,
            ..Material::default()
        };
        let materials = vec![
            SurfaceMaterial {
                front: material(0.8, 0.3, 0.2),
                back: material(0.2, 0.3, 0.8),
            },
            SurfaceMaterial::both_sides(material(0.4, 0.5, 0.4)),
        ];
        let mesh = Mesh {
            positions: vec![
                DVec3::new(0.5, 0.0, 0.5),
                DVec3::new(2.0, 0.0, 0.5),
                DVec3::new(1.2, 1.5, 0.2),
                DVec3::new(0.3, 0.2, 1.0),
                DVec3::new(-0.5, 1.4, 1.2),
                DVec3::new(-1.2, 0.2, 1.0),
            ],
            normals: Some(vec![
                DVec3::new(0.1, 0.3, 1.2),
                DVec3::new(0.4, 0.2, 0.9),
                DVec3::new(-0.2, 0.5, 1.0),
                DVec3::new(0.0, 0.2, -1.1),
                DVec3::new(0.3, -0.1, -0.8),
                DVec3::new(-0.2, 0.1, -1.0),
            ]),
            // The second triangle wound clockwise as seen: its back faces
            // the eye.
            indices: vec![[0, 1, 2], [3, 5, 4]],
        };
        RenderScene {
            objects: vec![
                Object {
                    shape: Shape::Sphere(Sphere {
                        center: DVec3::new(-1.0, 0.7, -0.5),
                        radius: 0.7,
                    }),
                    material: 0,
                },
                Object {
                    shape: Shape::Plane(Plane {
                        point: DVec3::ZERO,
                        normal: DVec3::Y,
                    }),
                    material: 1,
                },
                Object {
                    shape: Shape::Mesh(mesh),
                    material: 0,
                },
            ],
            lights: LightSet::new(model, lights, viewer).unwrap(),
            materials,
            material_names: vec!["a".into(), "b".into()],
            background: DVec4::new(0.1, 0.2, 0.3, 1.0),
            shading,
            samples: Samples::Uniform(4),
            shadows: true,
            precision: Precision::Reference,
            region: region.unwrap_or(Region {
                x: 0,
                y: 0,
                width: camera.width,
                height: camera.height,
            }),
            camera,
            probes: Vec::new(),
            encoding: Encoding::Linear,
            zero_normals: 0,
        }
    }

    /// The reference's colour of a shading point, without the diffuse and
    /// specular light of the lights its mask hides.
    fn reference_color(scene: &RenderScene, point: &ShadingPoint) -> DVec4 {
        let material = &scene.materials[point.material as usize];
        let mut b = reference::evaluate(
            &scene.lights,
            material,
            point.side,
            point.position,
            point.normal,
        );
        for (i, terms) in b.lights.iter_mut().enumerate() {
            if point.visible & (1 << i) == 0 {
                terms.diffuse = DVec3::ZERO;
                terms.specular = DVec3::ZERO;
            }
        }
        b.color(
            scene.lights.model.color_control,
            material.side(point.side).diffuse.w,
        )
    }

    /// Each pixel, composed of the reference's colours at its shading
    /// points, is the frame's pixel before its rounding to 8 bits: within
    /// half a step of it, and the f32 weights' rounding.
    #[test]
    fn the_shading_points_compose_the_frame_s_pixels() {
        let region = Region {
            x: 9,
            y: 5,
            width: 30,
            height: 22,
        };
        for (shading, region) in [
            (ShadingMode::PerPixel, None),
            (ShadingMode::PerVertex, None),
            (ShadingMode::PerVertex, Some(region)),
        ] {
            let scene = scene(shading, region);
            let renderer = Renderer::new(&scene);
            let frame = renderer.render(false, &|| false).unwrap();
            let pixels: Vec<u32> = (0..frame.width * frame.height).collect();
            let mut shading_of = PixelShading::default();
            renderer
                .shading_source()
                .unwrap()
                .shading(&pixels, &mut shading_of);
            let colors: Vec<DVec4> = shading_of
                .points
                .iter()
                .map(|p| reference_color(&scene, p))
                .collect();
            let (mut back, mut shadowed, mut misses) = (0, 0, 0);
            for &pixel in &pixels {
                let p = pixel as usize;
                let range = shading_of.pixels[p].clone();
                let terms = &shading_of.terms[range.start as usize..range.end as usize];
                let composed = terms
                    .iter()
                    .fold(shading_of.constant[p].as_dvec4(), |sum, &(point, w)| {
                        sum + f64::from(w) * colors[point as usize]
                    });
                let weights: f32 = terms.iter().map(|t| t.1).sum();
                misses += usize::from(weights < 0.99);
                let rgba = &frame.rgba[4 * p..4 * p + 4];
                for c in 0..4 {
                    let byte = film::encode(composed, Encoding::Linear)[c];
                    let value = composed[c].clamp(0.0, 1.0) * 255.0;
                    assert!(
                        (value - f64::from(rgba[c])).abs() <= 0.5 + 1e-4,
                        "{shading:?} pixel {pixel} channel {c}: {value} against {} ({byte})",
                        rgba[c]
                    );
                }
            }
            for point in &shading_of.points {
                back += usize::from(point.side == glint_lighting::Side::Back);
                shadowed += usize::from(point.visible != glint_lighting::LightMask::MAX);
            }
            // The scene shows what it is made to show.
            assert!(back > 0 && shadowed > 0 && misses > 0, "{shading:?}");
        }
    }
}
