//! The endpoints' answers computed offline, for the command line: `glint
//! shade`, `render` and `bake` read a request from a file and give the
//! bytes the endpoint would answer, computed by the same functions under
//! the server's default limits. A bad request is the endpoint's own
//! problem+json; a file that cannot be read or written is a problem too
//! (`unreadable`, `unwritable`), so the command line reports every failure
//! in one shape.

use std::io::Read;
use std::path::Path;

use base64::Engine;
use glint_trace::Region;

use crate::compare::image::ImageCompareResponse;
use crate::compare::{self, CompareResponse, ErrorOut};
use crate::problem::{Problem, ProblemKind};
use crate::render::{self, Form};
use crate::scene::{self, Limits};
use crate::{bake, shade};

/// The bytes of `path`, or of stdin for `-`.
pub fn read(path: &Path) -> Result<Vec<u8>, Problem> {
    let mut bytes = Vec::new();
    let read = if path.as_os_str() == "-" {
        std::io::stdin().read_to_end(&mut bytes).map(|_| ())
    } else {
        std::fs::read(path).map(|b| bytes = b)
    };
    read.map_err(|e| Problem::new(ProblemKind::Unreadable, format!("{}: {e}", path.display())))?;
    Ok(bytes)
}

/// Writes `bytes` to `path`.
pub fn write(path: &Path, bytes: &[u8]) -> Result<(), Problem> {
    std::fs::write(path, bytes)
        .map_err(|e| Problem::new(ProblemKind::Unwritable, format!("{}: {e}", path.display())))
}

/// What `POST /v1/shade` answers for the JSON `body`.
pub fn shade(body: &[u8]) -> Result<Vec<u8>, Problem> {
    let scene = scene::parse_shade(body, &Limits::default())?;
    Ok(shade::shade(&scene).to_json())
}

/// A render's answer in both of its forms that the command line writes.
pub struct Rendered {
    pub png: Vec<u8>,
    /// The JSON form, when asked for.
    pub json: Option<Vec<u8>>,
}

/// What `POST /v1/render` answers for `body` (the JSON request, or with
/// `model` the form's `request` part): the PNG, and with `json` the JSON
/// form too.
pub fn render(body: &[u8], model: Option<&[u8]>, json: bool) -> Result<Rendered, Problem> {
    let limits = Limits::default();
    let (scene, notes) = match model {
        None => (scene::parse_render(body, &limits)?, Vec::new()),
        Some(model) => scene::parse_model_render(Some(body), model, &limits)?,
    };
    if !json {
        let png = render::render_noted(&scene, notes, Form::Png, &|| false)
            .expect("never cancelled")
            .body;
        return Ok(Rendered { png, json: None });
    }
    let response = render::render_json_noted(&scene, notes, &|| false).expect("never cancelled");
    let png = base64::engine::general_purpose::STANDARD
        .decode(&response.png_base64)
        .expect("our own base64");
    let json = serde_json::to_vec(&response).expect("a response always serialises");
    Ok(Rendered {
        png,
        json: Some(json),
    })
}

/// The area `body` renders (its `region`, or the whole image), after
/// validating it as the endpoint would under no pixel limit: tiles of it
/// are sent to servers, each of which limits its own tile.
pub fn render_area(body: &[u8]) -> Result<Region, Problem> {
    let limits = Limits {
        max_vertices: usize::MAX,
        max_pixels: u64::MAX,
        ..Limits::default()
    };
    Ok(scene::parse_render(body, &limits)?.region)
}

/// What `POST /v1/shade` answers for `model` with the optional `request`
/// part: the baked GLB, or with `json` the JSON form.
pub fn bake(model: &[u8], request: Option<&[u8]>, json: bool) -> Result<Vec<u8>, Problem> {
    let scene = scene::parse_bake(request, model, &Limits::default())?;
    let form = if json {
        bake::Form::Json
    } else {
        bake::Form::Glb
    };
    Ok(bake::bake(scene, form).body.to_vec(model))
}

/// The request `body` with its precision the error budget `max_abs_error`
/// (`--max-abs-error`), as `{"precision": {"max_abs_error": E}}` asks.
pub fn with_budget(body: &[u8], max_abs_error: f64) -> Result<Vec<u8>, Problem> {
    let mut request = json_object(body, "the request")?;
    request.insert(
        "precision".to_owned(),
        serde_json::json!({ "max_abs_error": max_abs_error }),
    );
    Ok(serde_json::to_vec(&request).expect("JSON serialises"))
}

/// `body` as a JSON object; `what` names it in the problem.
fn json_object(
    body: &[u8],
    what: &str,
) -> Result<serde_json::Map<String, serde_json::Value>, Problem> {
    serde_json::from_slice(body).map_err(|e| {
        Problem::new(
            ProblemKind::Malformed,
            format!("{what} is not a JSON object: {e}"),
        )
        .at("")
    })
}

/// What `POST /v1/compare` answers, for the command line.
#[derive(Debug)]
pub enum Compared {
    /// Per-vertex colours: JSON, or a GLB's `COLOR_0`.
    Vertices(CompareResponse),
    /// A PNG.
    Image(Box<ImageCompareResponse>),
}

impl Compared {
    pub fn within_bound(&self) -> bool {
        self.error().within_bound
    }

    fn error(&self) -> &ErrorOut {
        match self {
            Compared::Vertices(r) => &r.error,
            Compared::Image(r) => &r.error,
        }
    }

    /// The summary for a terminal: the error, then the diagnosis, one
    /// explanation a line, those that explain marked.
    pub fn summary(&self) -> String {
        use std::fmt::Write;
        let (diagnosis, precision) = match self {
            Compared::Vertices(r) => (&r.diagnosis, &r.precision),
            Compared::Image(r) => (&r.diagnosis, &r.precision),
        };
        let e = self.error();
        let psnr = match e.psnr_db {
            Some(db) if db.is_finite() => format!("  PSNR {db:.1} dB"),
            Some(_) => "  PSNR ∞".to_owned(),
            None => String::new(),
        };
        let mut out = format!(
            "max {:.3e}  mean {:.3e}  p99 {:.3e}  8-bit channels differing {:.2}%{psnr}: {} \
             the bound {:e} of {}\n",
            e.max_abs,
            e.mean_abs,
            e.p99_abs,
            100.0 * e.differing_8bit,
            if e.within_bound { "within" } else { "outside" },
            e.bound.unwrap_or(precision.max_abs_error),
            serde_json::to_value(precision.mode).expect("a mode serialises"),
        );
        if diagnosis.iter().all(|d| !d.explains) {
            out.push_str("no deviation of the catalogue explains the candidate\n");
        }
        for d in diagnosis {
            let _ = writeln!(
                out,
                "{} {:<48} max {:.3e}  mean {:.3e}  {}",
                if d.explains { "*" } else { " " },
                d.deviations.join(" + "),
                d.max_abs,
                d.mean_abs,
                d.detail
            );
        }
        out
    }
}

/// What `POST /v1/compare` answers for `request` and `candidate`, told
/// apart by their first bytes: a PNG (the request a `/v1/render` request,
/// as the form's `request` and `image` parts), a GLB (whose `COLOR_0`
/// holds the candidate, as the form's `request` and `model` parts), or a
/// JSON file holding what the request's `candidate` holds
/// (`{"colors": [...]}`).
pub fn compare(request: &[u8], candidate: &[u8]) -> Result<Compared, Problem> {
    const PNG: &[u8] = b"\x89PNG\r\n\x1a\n";
    const GLB: &[u8] = b"glTF";
    let limits = Limits::default();
    if candidate.starts_with(PNG) {
        let scene = scene::parse_compare_image(request, candidate, &limits)?;
        let compared = compare::image::compare_image(&scene, &|| false).expect("never cancelled");
        return Ok(Compared::Image(Box::new(compared.response)));
    }
    if candidate.starts_with(GLB) {
        let scene = scene::parse_compare_model(Some(request), candidate, &limits)?;
        return Ok(Compared::Vertices(compare::compare(&scene)?));
    }
    let mut body = json_object(request, "the request")?;
    let candidate = json_object(candidate, "the candidate")?;
    body.insert("candidate".to_owned(), candidate.into());
    let body = serde_json::to_vec(&body).expect("JSON serialises");
    let scene = scene::parse_compare(&body, &limits)?;
    Ok(Compared::Vertices(compare::compare(&scene)?))
}

/// The problem the command line reports when a tile is asked for that the
/// image does not have.
pub fn no_such_tile(index: usize, tiles: usize) -> Problem {
    Problem::new(
        ProblemKind::Invalid,
        format!("--tile {index}: the image has {tiles} tiles, numbered from 0"),
    )
}

/// The problem of a render asked for with nowhere to put it.
pub fn no_output() -> Problem {
    Problem::new(
        ProblemKind::NoOutput,
        "give -o OUT.png, or --json to print the JSON form",
    )
}
