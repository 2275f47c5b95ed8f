//! `glint`: the service, and the same engine offline on a scene file.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use base64::Engine;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use glint::config::ServeConfig;
use glint::fanout::{self, FanoutError, Grid, Plan};
use glint::problem::{Problem, ProblemKind};
use glint::render;
use glint::scene::{self, Limits};
use glint::shade;

#[derive(Parser)]
#[command(version, about = "OpenGL fixed-function lighting as a service")]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Flags of `serve`, which runs when no subcommand is given.
    #[command(flatten)]
    serve: ServeConfig,
}

#[derive(Subcommand)]
enum Command {
    /// Start the HTTP service (the default).
    Serve(Box<ServeConfig>),
    /// Light a /v1/shade request from FILE (`-` for stdin) and print the
    /// response JSON.
    Shade { file: PathBuf },
    /// Render a /v1/render request from FILE (`-` for stdin) to a PNG: here,
    /// or through a glint service as tiles (--via).
    Render(Box<RenderArgs>),
    /// Bake a glTF model (GLB) as /v1/shade would: GL's colours in its
    /// COLOR_0, written to OUT.glb (or the JSON answer printed).
    Bake(BakeArgs),
    /// Exit 0 when the service is ready (URL answers 200), 1 otherwise: the
    /// probe of an image with no shell or curl.
    Healthcheck {
        /// The URL to ask [default: /readyz on 127.0.0.1 at the port of
        /// GLINT_LISTEN, 8080 without it].
        #[arg(long)]
        url: Option<String>,
        /// Time to wait for the answer, in milliseconds.
        #[arg(long, default_value_t = 5_000)]
        timeout_ms: u64,
    },
}

#[derive(clap::Args)]
struct BakeArgs {
    /// The model, a GLB (`-` for stdin).
    model: PathBuf,
    /// The request's lighting and options, as the `request` part of the
    /// endpoint's form takes them.
    #[arg(long, value_name = "REQ.json")]
    request: Option<PathBuf>,
    /// Where to write the baked model (required unless --json).
    #[arg(short, long, value_name = "OUT.glb", required_unless_present = "json")]
    output: Option<PathBuf>,
    /// Print the JSON form of the answer instead, with the runs of each
    /// primitive.
    #[arg(long, conflicts_with = "output")]
    json: bool,
}

#[derive(clap::Args)]
struct RenderArgs {
    file: PathBuf,
    /// A glTF model (GLB) whose triangles join the scene; FILE is then the
    /// `request` part of the endpoint's form.
    #[arg(long, value_name = "MODEL.glb", conflicts_with_all = ["via", "tile"])]
    model: Option<PathBuf>,
    /// Where to write the PNG (required unless --json).
    #[arg(short, long, required_unless_present = "json")]
    output: Option<PathBuf>,
    /// Print the JSON form of the response instead (with -o, the PNG is
    /// written as well).
    #[arg(long, conflicts_with = "via")]
    json: bool,
    /// Render through the glint service at URL (a replica, a load balancer,
    /// a Kubernetes Service) as tiles, sent concurrently, retried when a
    /// retry may succeed, and stitched into the single request's PNG.
    #[arg(long, value_name = "URL")]
    via: Option<String>,
    /// The tiles: columns × rows of the image (or of its region).
    #[arg(long, value_name = "CxR", default_value = "4x4")]
    tiles: Grid,
    /// Render only tile I of --tiles, counted from 0 row by row from the
    /// top left: the PNG of its region (one pod of an Indexed Job does this).
    #[arg(long, value_name = "I", conflicts_with_all = ["via", "json"])]
    tile: Option<usize>,
    /// With --via: tiles in flight at once.
    #[arg(long, default_value_t = 4, requires = "via",
          value_parser = clap::builder::TypedValueParser::map(
              clap::value_parser!(u16).range(1..), usize::from))]
    parallel: usize,
    /// With --via: tries of one tile, the first included.
    #[arg(long, default_value_t = 6, requires = "via",
          value_parser = clap::value_parser!(u32).range(1..))]
    tries: u32,
    /// With --via: seconds one try of a tile may take.
    #[arg(long, default_value_t = 300, requires = "via")]
    try_timeout_secs: u64,
    /// With --via: print what was done (each tile's replica and tries) as
    /// JSON on stdout.
    #[arg(long, requires = "via")]
    report: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        None => serve(&cli.serve),
        Some(Command::Serve(config)) => serve(&config),
        Some(Command::Shade { file }) => offline(shade(&file)),
        Some(Command::Render(args)) => match &args.via {
            Some(via) => render_via(&args, via),
            None => match render(&args) {
                // The PNG went to its file: nothing to print.
                Ok(out) if out.is_empty() => ExitCode::SUCCESS,
                result => offline(result),
            },
        },
        Some(Command::Bake(args)) => match bake(&args) {
            // The model went to its file: nothing to print.
            Ok(out) if out.is_empty() => ExitCode::SUCCESS,
            result => offline(result),
        },
        Some(Command::Healthcheck { url, timeout_ms }) => {
            healthcheck(url, Duration::from_millis(timeout_ms))
        }
    }
}

fn serve(config: &ServeConfig) -> ExitCode {
    // Written out when dropped, after the server and its last log line.
    let _logs = glint::logging::init(config.logs());
    let runtime = match tokio::runtime::Runtime::new() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("glint: cannot start the async runtime: {e}");
            return ExitCode::FAILURE;
        }
    };
    match runtime.block_on(glint::http::serve(config)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            tracing::error!(error = %e, "glint stopped");
            ExitCode::FAILURE
        }
    }
}

/// Prints a command's output, or its problem+json on stderr with a failure
/// exit code.
fn offline(result: Result<Vec<u8>, Problem>) -> ExitCode {
    match result {
        Ok(out) => {
            let mut stdout = std::io::stdout().lock();
            let _ = stdout.write_all(&out).and_then(|_| stdout.write_all(b"\n"));
            ExitCode::SUCCESS
        }
        Err(problem) => {
            eprintln!(
                "{}",
                serde_json::to_string(&problem).expect("a problem always serialises")
            );
            ExitCode::FAILURE
        }
    }
}

fn read_input(file: &PathBuf) -> Result<Vec<u8>, Problem> {
    let mut bytes = Vec::new();
    let read = if file.as_os_str() == "-" {
        std::io::stdin().read_to_end(&mut bytes).map(|_| ())
    } else {
        std::fs::read(file).map(|b| bytes = b)
    };
    read.map_err(|e| Problem::new(ProblemKind::Unreadable, format!("{}: {e}", file.display())))?;
    Ok(bytes)
}

fn shade(file: &PathBuf) -> Result<Vec<u8>, Problem> {
    let body = read_input(file)?;
    let scene = scene::parse_shade(&body, &Limits::default()).map_err(Problem::from)?;
    Ok(shade::shade(&scene).to_json())
}

fn write_file(bytes: &[u8], path: &Path) -> Result<(), Problem> {
    std::fs::write(path, bytes)
        .map_err(|e| Problem::new(ProblemKind::Unwritable, format!("{}: {e}", path.display())))
}

/// Renders FILE (or its tile `--tile`): the PNG to `output`, and with
/// `json` the JSON form to stdout. Prints nothing else on success.
fn render(args: &RenderArgs) -> Result<Vec<u8>, Problem> {
    let (output, json) = (args.output.as_deref(), args.json);
    let mut body = read_input(&args.file)?;
    if let Some(index) = args.tile {
        let plan = Plan::new(&body, args.tiles)?;
        let Some(&tile) = plan.tiles.get(index) else {
            return Err(Problem::new(
                ProblemKind::Invalid,
                format!(
                    "--tile {index}: the image has {} tiles, numbered from 0",
                    plan.tiles.len()
                ),
            ));
        };
        body = plan.body(tile);
    }
    let (scene, notes) = match &args.model {
        None => (scene::parse_render(&body, &Limits::default()), Vec::new()),
        Some(model) => {
            let model = read_input(model)?;
            match scene::parse_model_render(Some(&body), &model, &Limits::default()) {
                Ok((scene, notes)) => (Ok(scene), notes),
                Err(e) => (Err(e), Vec::new()),
            }
        }
    };
    let scene = scene.map_err(Problem::from)?;
    match (output, json) {
        (None, false) => Err(Problem::new(
            ProblemKind::NoOutput,
            "give -o OUT.png, or --json to print the JSON form",
        )),
        (Some(path), false) => {
            write_file(&render::render_png(&scene), path)?;
            Ok(Vec::new())
        }
        (output, true) => {
            let response =
                render::render_json_noted(&scene, notes, &|| false).expect("never cancelled");
            if let Some(path) = output {
                let png = base64::engine::general_purpose::STANDARD
                    .decode(&response.png_base64)
                    .expect("our own base64");
                write_file(&png, path)?;
            }
            Ok(serde_json::to_vec(&response).expect("a response always serialises"))
        }
    }
}

/// `glint bake MODEL.glb`: the baked model to `-o`, or the JSON answer to
/// stdout. Prints nothing else on success.
fn bake(args: &BakeArgs) -> Result<Vec<u8>, Problem> {
    let model = read_input(&args.model)?;
    let request = args.request.as_ref().map(read_input).transpose()?;
    let scene =
        scene::parse_bake(request.as_deref(), &model, &Limits::default()).map_err(Problem::from)?;
    match &args.output {
        Some(path) if !args.json => {
            let baked = glint::bake::bake(scene, glint::bake::Form::Glb);
            write_file(&baked.body.to_vec(&model), path)?;
            Ok(Vec::new())
        }
        _ => Ok(glint::bake::bake(scene, glint::bake::Form::Json)
            .body
            .to_vec(&model)),
    }
}

/// `glint render FILE --via URL`: the tiles through the service, stitched.
fn render_via(args: &RenderArgs, via: &str) -> ExitCode {
    let output = args
        .output
        .as_deref()
        .expect("-o is required without --json");
    let body = match read_input(&args.file) {
        Ok(body) => body,
        Err(problem) => return offline(Err(problem)),
    };
    let options = fanout::Options {
        via: via.to_owned(),
        grid: args.tiles,
        parallel: args.parallel,
        tries: args.tries,
        try_timeout: Duration::from_secs(args.try_timeout_secs),
        progress: true,
    };
    let rendered = client_runtime().and_then(|rt| {
        rt.block_on(fanout::render(&body, &options))
            .map_err(|e| match &e {
                FanoutError::Request(problem) => {
                    serde_json::to_string(problem).expect("a problem always serialises")
                }
                // The server's own problem+json, last, as the offline
                // commands print theirs.
                FanoutError::Refused { body, .. } => format!("glint: {e}:\n{body}"),
                _ => format!("glint: {e}"),
            })
    });
    let done = match rendered {
        Ok(done) => done,
        Err(said) => {
            eprintln!("{said}");
            return ExitCode::FAILURE;
        }
    };
    if let Err(problem) = write_file(&done.png, output) {
        return offline(Err(problem));
    }
    if args.report {
        println!(
            "{}",
            serde_json::to_string(&done.report).expect("a report serialises")
        );
    }
    ExitCode::SUCCESS
}

/// `glint healthcheck`: 0 when `url` answers 200 within `timeout`.
fn healthcheck(url: Option<String>, timeout: Duration) -> ExitCode {
    let url = url.unwrap_or_else(|| {
        let port = std::env::var("GLINT_LISTEN")
            .ok()
            .and_then(|listen| listen.parse::<std::net::SocketAddr>().ok())
            .map_or(8080, |addr| addr.port());
        format!("http://127.0.0.1:{port}/readyz")
    });
    let answered = client_runtime().and_then(|rt| {
        rt.block_on(async {
            let client = reqwest::Client::builder()
                .no_proxy()
                .timeout(timeout)
                .build()
                .map_err(|e| e.to_string())?;
            let response = client
                .get(&url)
                .send()
                .await
                .map_err(|e| fanout::describe(&e))?;
            Ok(response.status())
        })
    });
    match answered {
        Ok(status) if status == reqwest::StatusCode::OK => ExitCode::SUCCESS,
        Ok(status) => {
            eprintln!("glint: {url} answered {status}");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("glint: {url}: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The async runtime of the client commands.
fn client_runtime() -> Result<tokio::runtime::Runtime, String> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| format!("glint: cannot start the async runtime: {e}"))
}
