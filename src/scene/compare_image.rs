//! `POST /v1/compare` with an image: the `request` part, a render request
//! (validated as `/v1/render` validates it, its faults located under
//! `/request`), and the `image` part, the candidate's PNG of the render's
//! size (its faults at `/image`).
//!
//! The PNG is read with the render's own pixel count as its limit, so that
//! a PNG whose header claims more pixels than the render has is refused
//! from its header, before anything is allocated for it (see
//! [`glint_compare::image::read_png`]).

use glam::Vec4;
use glint_compare::Options;
use glint_compare::image::{PngError, read_png};
use glint_trace::{Encoding, RenderScene, Samples};

use super::compare::options;
use super::model::in_request;
use super::{Limits, RequestError, parse_json, render_scene, wire};

type Result<T> = std::result::Result<T, RequestError>;

/// A validated compare of an image.
#[derive(Clone, Debug)]
pub struct ImageCompareScene {
    pub render: RenderScene,
    /// The candidate's pixels as linear colours, row by row: its channels
    /// decoded as the request's `encoding` says GL's PNG is encoded.
    pub candidate: Vec<Vec4>,
    /// The candidate's PNG has an alpha channel (then alpha is compared).
    pub alpha: bool,
    /// Half a step of the candidate's channels, as stored (see
    /// [`glint_compare::image::PngImage::half_step`]).
    pub half_step: f64,
    pub options: Options,
}

/// Parses and validates the two parts of an image compare.
pub fn parse_compare_image(
    request: &[u8],
    image: &[u8],
    limits: &Limits,
) -> Result<ImageCompareScene> {
    let request: wire::RenderRequest = parse_json(request).map_err(in_request)?;
    let camera = request.compare_form().map_err(in_request)?;
    let render = render_scene(&request, camera, limits).map_err(in_request)?;
    if let Samples::Adaptive { .. } = render.samples.effective() {
        return Err(RequestError::invalid(
            "/request/samples",
            "an image compare takes a count of samples: adaptive sampling chooses each \
             pixel's samples from the colours it finds, which a port's colours would change",
        ));
    }
    let options = options(request.worst, request.tolerance, "/request")?;
    let region = render.region;
    let size = (region.width, region.height);
    let wrong_size = |found: (u32, u32)| {
        RequestError::invalid(
            "/image",
            format!(
                "the candidate is {}×{}, the render {}×{}: give a PNG of the render's size \
                 (its region's, where it names one)",
                found.0, found.1, size.0, size.1
            ),
        )
    };
    let png = read_png(image, region.pixels()).map_err(|e| match e {
        PngError::TooLarge { width, height } => wrong_size((width, height)),
        PngError::Unreadable(_) => RequestError::malformed("/image", e.to_string()),
    })?;
    if (png.width, png.height) != size {
        return Err(wrong_size((png.width, png.height)));
    }
    let candidate = match render.encoding {
        Encoding::Linear => png.pixels.clone(),
        Encoding::Srgb => png.pixels.iter().map(|&c| srgb_decoded(c)).collect(),
    };
    Ok(ImageCompareScene {
        render,
        candidate,
        alpha: png.alpha,
        half_step: png.half_step(),
        options,
    })
}

/// An sRGB-encoded colour's RGB decoded to linear; alpha stays linear.
pub fn srgb_decoded(c: Vec4) -> Vec4 {
    let decode = |v: f32| crate::bake::srgb_to_linear(f64::from(v)) as f32;
    Vec4::new(decode(c.x), decode(c.y), decode(c.z), c.w)
}
