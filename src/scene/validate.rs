//! From wire types to domain types: defaults applied, every rule of the
//! contract checked once, every failure located by JSON Pointer.

use glam::{DVec3, DVec4};

use glint_lighting::{
    self as lighting, ColorControl, Light, LightModel, LightPosition, LightSet, MAX_COLOR,
    MAX_COORDINATE, MAX_RAW_NORMAL, Material, SpecularModel, Spot, SurfaceMaterial, Viewer,
};

use super::{At, Limits, RequestError, ShadeScene, wire};

type Result<T> = std::result::Result<T, RequestError>;

/// Validates a `/v1/shade` request.
pub fn shade_scene(request: &wire::ShadeRequest, limits: &Limits) -> Result<ShadeScene> {
    vertex_scene(request, request.json_form()?, limits)
}

/// Validates a shade request with its `vertices` (of its JSON body).
pub(super) fn vertex_scene(
    request: &wire::ShadeRequest,
    vertices: &wire::Vertices,
    limits: &Limits,
) -> Result<ShadeScene> {
    let viewer = match &request.view {
        None => None,
        Some(view) => Some(view_viewer(
            view,
            request_local_viewer(&request.light_model),
        )?),
    };
    let lights = light_set(
        request.light_model.as_ref(),
        request.lights.as_ref(),
        viewer,
        limits,
    )?;
    let front = match &request.material {
        Some(m) => material(m, &At::pointer("/material"))?,
        None => Material::default(),
    };
    let back = match &request.back_material {
        Some(m) => material(m, &At::pointer("/back_material"))?,
        None => front,
    };

    let count = vertices.positions.len();
    if count > limits.max_vertices {
        return Err(RequestError::over_limit(
            "/vertices/positions",
            format!(
                "{count} vertices, over this server's limit of {}",
                limits.max_vertices
            ),
        ));
    }
    let raw_limit = (!lights.model.normalize_normals).then_some(MAX_RAW_NORMAL);
    let positions = points(&vertices.positions, &At::pointer("/vertices/positions"))?;
    let normals = normals(
        &vertices.normals,
        positions.len(),
        raw_limit,
        &At::pointer("/vertices/normals"),
    )?;
    let zero_normals = normals.iter().filter(|n| **n == DVec3::ZERO).count();

    Ok(ShadeScene {
        lights,
        material: SurfaceMaterial { front, back },
        positions,
        normals,
        precision: precision(request.precision, "")?,
        terms: request.terms.unwrap_or_default(),
        zero_normals,
    })
}

/// Checks a count that the contract bounds at `contract` and this server
/// at `server` (at most the contract's): past the contract's bound the
/// request is invalid (422), past the server's only it is over a limit of
/// this server (413).
pub(super) fn count_within(
    pointer: &str,
    what: &str,
    count: usize,
    contract: usize,
    server: usize,
) -> Result<()> {
    if count > contract {
        return Err(RequestError::invalid(
            pointer,
            format!("{count} {what}: the contract allows at most {contract}"),
        ));
    }
    if count > server {
        return Err(RequestError::over_limit(
            pointer,
            format!("{count} {what}, over this server's limit of {server}"),
        ));
    }
    Ok(())
}

/// The precision a request asks for: a tier by its name, or the cheapest
/// tier whose documented bound is at most its budget (an invalid request
/// when even the reference's is larger). `at` is where the request is:
/// `""`, or `/request` in a form.
pub(super) fn precision(
    requested: Option<wire::PrecisionRequest>,
    at: &str,
) -> Result<glint_lighting::Precision> {
    use glint_lighting::Precision;
    match requested {
        None => Ok(Precision::default()),
        Some(wire::PrecisionRequest::Tier(tier)) => Ok(tier.into()),
        Some(wire::PrecisionRequest::Budget(budget)) => {
            // From the cheapest tier to the most precise.
            [Precision::Fast, Precision::Accurate, Precision::Reference]
                .into_iter()
                .find(|tier| tier.max_abs_error() <= budget)
                .ok_or_else(|| {
                    RequestError::invalid(
                        format!("{at}/precision/max_abs_error"),
                        format!(
                            "a budget of {budget:e}: no tier is that precise; `reference`'s \
                             bound, the f32 rounding of its colours, is {:e}",
                            Precision::Reference.max_abs_error()
                        ),
                    )
                })
        }
    }
}

/// Whether the request's light model asks for a local viewer.
pub(super) fn request_local_viewer(model: &Option<wire::LightModel>) -> bool {
    model
        .as_ref()
        .and_then(|m| m.local_viewer)
        .unwrap_or(LightModel::default().local_viewer)
}

/// The viewer of a request with a view: the eye point, or the direction from
/// the target to the eye.
pub(super) fn view_viewer(view: &wire::View, local: bool) -> Result<Viewer> {
    let eye = point(&view.eye, &At::pointer("/view/eye"))?;
    let target = point(&view.target, &At::pointer("/view/target"))?;
    if let Some(up) = &view.up {
        vector(up, &At::pointer("/view/up"))?;
    }
    if eye == target {
        return Err(RequestError::invalid(
            "/view/target",
            "the target is the eye: the view has no direction",
        ));
    }
    Ok(if local {
        Viewer::Local(eye)
    } else {
        Viewer::Infinite(lighting::unit_or_zero(eye - target))
    })
}

/// Validates the light model and the lights shared by every endpoint;
/// `viewer` is `None` for eye space.
pub fn light_set(
    model: Option<&wire::LightModel>,
    lights: Option<&wire::Lights>,
    viewer: Option<Viewer>,
    limits: &Limits,
) -> Result<LightSet> {
    let model = light_model(model.cloned().unwrap_or_default())?;
    // Past lighting::MAX_LIGHTS the wire type only counts them.
    let count = lights.map_or(0, wire::Lights::count);
    count_within(
        "/lights",
        "lights",
        count,
        lighting::MAX_LIGHTS,
        limits.max_lights,
    )?;
    let at = At::pointer("/lights");
    let lights = lights
        .map_or(&[][..], |l| &l[..])
        .iter()
        .enumerate()
        .map(|(i, l)| light(l, &at.index(i)))
        .collect::<Result<Vec<_>>>()?;
    let viewer = viewer.unwrap_or_else(|| LightSet::eye_space_viewer(model.local_viewer));
    LightSet::new(model, lights, viewer)
        .map_err(|e| RequestError::over_limit("/lights", e.to_string()))
}

fn light_model(m: wire::LightModel) -> Result<LightModel> {
    let d = LightModel::default();
    Ok(LightModel {
        ambient: color(m.ambient, d.ambient, &At::pointer("/light_model/ambient"))?,
        local_viewer: m.local_viewer.unwrap_or(d.local_viewer),
        two_side: m.two_side.unwrap_or(d.two_side),
        color_control: match m.color_control {
            None => d.color_control,
            Some(wire::ColorControl::Single) => ColorControl::Single,
            Some(wire::ColorControl::SeparateSpecular) => ColorControl::SeparateSpecular,
        },
        specular_model: match m.specular_model {
            None => d.specular_model,
            Some(wire::SpecularModel::BlinnPhong) => SpecularModel::BlinnPhong,
            Some(wire::SpecularModel::Phong) => SpecularModel::Phong,
        },
        attenuation_clamp: m.attenuation_clamp.unwrap_or(d.attenuation_clamp),
        normalize_normals: m.normalize_normals.unwrap_or(d.normalize_normals),
    })
}

/// Validates one material found at `at`.
pub fn material(m: &wire::Material, at: &At) -> Result<Material> {
    let d = Material::default();
    let shininess = m.shininess.unwrap_or(d.shininess);
    if !(shininess.is_finite() && shininess >= 0.0) {
        return Err(RequestError::invalid(
            at.field("shininess"),
            format!("shininess must be a finite number >= 0, not {shininess}"),
        ));
    }
    Ok(Material {
        ambient: color(m.ambient, d.ambient, &at.field("ambient"))?,
        diffuse: color(m.diffuse, d.diffuse, &at.field("diffuse"))?,
        specular: color(m.specular, d.specular, &at.field("specular"))?,
        emission: color(m.emission, d.emission, &at.field("emission"))?,
        shininess,
    })
}

fn light(l: &wire::Light, at: &At) -> Result<Light> {
    let d = Light::default();
    let position = match l.position {
        None => d.position,
        Some(p) => light_position(p, &at.field("position"))?,
    };
    let attenuation = l.attenuation.unwrap_or(d.attenuation);
    for (k, value) in attenuation.iter().enumerate() {
        if !(value.is_finite() && *value >= 0.0) {
            return Err(RequestError::invalid(
                at.field("attenuation").index(k),
                format!("attenuation coefficients must be finite and >= 0, not {value}"),
            ));
        }
    }
    if attenuation == [0.0; 3] {
        return Err(RequestError::invalid(
            at.field("attenuation"),
            "attenuation coefficients are all zero: 1/(k0 + k1·d + k2·d²) would be infinite",
        ));
    }
    Ok(Light {
        position,
        ambient: color(l.ambient, d.ambient, &at.field("ambient"))?,
        diffuse: color(l.diffuse, d.diffuse, &at.field("diffuse"))?,
        specular: color(l.specular, d.specular, &at.field("specular"))?,
        attenuation,
        spot: match &l.spot {
            None => d.spot,
            Some(s) => spot(s, &at.field("spot"))?,
        },
    })
}

fn light_position(p: [f64; 4], at: &At) -> Result<LightPosition> {
    finite(&p).map_err(|f| f.at(at))?;
    let [x, y, z, w] = p;
    let xyz = DVec3::new(x, y, z);
    if w == 0.0 {
        let towards = lighting::unit_or_zero(xyz);
        if towards == DVec3::ZERO {
            return Err(RequestError::invalid(
                at,
                "a directional light (w = 0) needs a non-zero direction",
            ));
        }
        Ok(LightPosition::Directional(towards))
    } else {
        let point = xyz / w;
        if point.abs().max_element() > MAX_COORDINATE {
            return Err(RequestError::invalid(
                at,
                format!(
                    "the position (x, y, z)/w is farther than {MAX_COORDINATE:e} from the \
                     origin; use w = 0 for a light at infinity"
                ),
            ));
        }
        Ok(LightPosition::Positional(point))
    }
}

fn spot(s: &wire::Spot, at: &At) -> Result<Spot> {
    let d = Spot::default();
    let cutoff = s.cutoff.unwrap_or(d.cutoff);
    if !(cutoff == 180.0 || (0.0..=90.0).contains(&cutoff)) {
        return Err(RequestError::invalid(
            at.field("cutoff"),
            format!("a spot cutoff must be 180 or lie in [0, 90], not {cutoff}"),
        ));
    }
    let exponent = s.exponent.unwrap_or(d.exponent);
    if !(exponent.is_finite() && exponent >= 0.0) {
        return Err(RequestError::invalid(
            at.field("exponent"),
            format!("a spot exponent must be a finite number >= 0, not {exponent}"),
        ));
    }
    let direction = match &s.direction {
        None => d.direction,
        Some(v) => {
            let at = at.field("direction");
            let unit = lighting::unit_or_zero(vector(v, &at)?);
            if unit == DVec3::ZERO && cutoff != 180.0 {
                return Err(RequestError::invalid(
                    at,
                    "a spotlight needs a non-zero direction",
                ));
            }
            unit
        }
    };
    Ok(Spot {
        direction,
        exponent,
        cutoff,
    })
}

pub(super) fn color(c: Option<wire::Color>, default: DVec4, at: &At) -> Result<DVec4> {
    let Some(wire::Color(c)) = c else {
        return Ok(default);
    };
    for (i, v) in c.iter().enumerate() {
        if !(v.is_finite() && v.abs() <= MAX_COLOR) {
            return Err(RequestError::invalid(
                at.index(i),
                format!("colour components must be finite and within ±{MAX_COLOR:e}, not {v}"),
            ));
        }
    }
    Ok(DVec4::from_array(c))
}

/// A point: finite, within [`MAX_COORDINATE`].
pub fn point(p: &[f64; 3], at: &At) -> Result<DVec3> {
    point_fault(p).map_err(|f| f.at(at))
}

/// Points found at `at` (`/vertices/positions`, `/objects/2/mesh/positions`).
pub(super) fn points(points: &[[f64; 3]], at: &At) -> Result<Vec<DVec3>> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| point_fault(p).map_err(|f| f.at(&at.index(i))))
        .collect()
}

/// One normal per point, found at `at`; `raw_limit` bounds them when they
/// are used as given.
pub(super) fn normals(
    normals: &[[f64; 3]],
    points: usize,
    raw_limit: Option<f64>,
    at: &At,
) -> Result<Vec<DVec3>> {
    if normals.len() != points {
        return Err(RequestError::invalid(
            at,
            format!(
                "{} normals for {points} positions: give one normal per position",
                normals.len()
            ),
        ));
    }
    normals
        .iter()
        .enumerate()
        .map(|(i, n)| normal_fault(n, raw_limit).map_err(|f| f.at(&at.index(i))))
        .collect()
}

/// A vector of finite numbers.
pub fn vector(v: &[f64; 3], at: &At) -> Result<DVec3> {
    vector_fault(v).map_err(|f| f.at(at))
}

/// What is wrong with a vector, before its pointer is known: checking a
/// million vertices formats a pointer only for the one at fault.
struct Fault {
    /// The component at fault, when it is one.
    component: Option<usize>,
    message: String,
}

impl Fault {
    fn at(self, at: &At) -> RequestError {
        match self.component {
            Some(i) => RequestError::invalid(at.index(i), self.message),
            None => RequestError::invalid(at, self.message),
        }
    }
}

fn finite(values: &[f64]) -> std::result::Result<(), Fault> {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Fault {
            component: Some(i),
            message: "numbers must be finite".to_owned(),
        }),
    }
}

fn vector_fault(v: &[f64; 3]) -> std::result::Result<DVec3, Fault> {
    finite(v)?;
    Ok(DVec3::from_array(*v))
}

fn point_fault(p: &[f64; 3]) -> std::result::Result<DVec3, Fault> {
    let v = vector_fault(p)?;
    if v.abs().max_element() > MAX_COORDINATE {
        return Err(Fault {
            component: None,
            message: format!("coordinates must lie within ±{MAX_COORDINATE:e}"),
        });
    }
    Ok(v)
}

/// A normal: finite, and within [`MAX_RAW_NORMAL`] when used as given.
fn normal_fault(n: &[f64; 3], raw_limit: Option<f64>) -> std::result::Result<DVec3, Fault> {
    let v = vector_fault(n)?;
    match raw_limit {
        Some(limit) if v.abs().max_element() > limit => Err(Fault {
            component: None,
            message: format!(
                "with normalize_normals off, normal components must lie within ±{limit:e}"
            ),
        }),
        _ => Ok(v),
    }
}
