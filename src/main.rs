//! `glint`: the service, and the same engine offline on a scene file.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use clap::{Parser, Subcommand};
use glint::config::ServeConfig;
use glint::offline;
use glint::problem::Problem;
use glint_client::fanout::{self, FanoutError, Grid, Plan};

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
    Shade {
        file: PathBuf,
        #[command(flatten)]
        budget: Budget,
    },
    /// Render a /v1/render request from FILE (`-` for stdin) to a PNG: here,
    /// or through a glint service as tiles (--via).
    Render(Box<RenderArgs>),
    /// Bake a glTF model (GLB) as /v1/shade would: GL's colours in its
    /// COLOR_0, written to OUT.glb (or the JSON answer printed).
    Bake(BakeArgs),
    /// Compare a port's colours with GL's as /v1/compare would: CANDIDATE
    /// is a JSON file of the request's `candidate` (`{"colors": [[r, g, b,
    /// a], ...]}`) or a GLB whose COLOR_0 holds them, REQUEST then a
    /// /v1/shade request; or a PNG, REQUEST then the /v1/render request it
    /// renders. Prints the error and the diagnosis; exits 0 when the
    /// candidate is within the bound, 1 when not, 2 on a bad request.
    Compare {
        request: PathBuf,
        candidate: PathBuf,
    },
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

/// The precision as an error budget, in place of the request's own.
#[derive(clap::Args)]
struct Budget {
    /// Evaluate with the cheapest tier whose documented bound is at most E
    /// (the request's `"precision": {"max_abs_error": E}`).
    #[arg(long, value_name = "E")]
    max_abs_error: Option<f64>,
}

impl Budget {
    /// The request `body` with this budget as its precision, when given.
    fn applied(&self, body: Vec<u8>) -> Result<Vec<u8>, Problem> {
        match self.max_abs_error {
            None => Ok(body),
            Some(e) => offline::with_budget(&body, e),
        }
    }
}

#[derive(clap::Args)]
struct BakeArgs {
    /// The model, a GLB (`-` for stdin).
    model: PathBuf,
    #[command(flatten)]
    budget: Budget,
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
    #[command(flatten)]
    budget: Budget,
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

/// mimalloc rather than glibc's allocator: a request allocates on one
/// thread what another frees (the log's lines, the pool's results), which
/// glibc serves with a lock per arena and mimalloc without one.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> ExitCode {
    let cli = Cli::parse();
    // A forced build of the lighting kernel that this CPU cannot run stops
    // every command here, not at its first lighting.
    if let Err(e) = glint_lighting::kernel::InstructionSet::check_env() {
        eprintln!("glint: {e}");
        return ExitCode::FAILURE;
    }
    match cli.command {
        None => serve(&cli.serve),
        Some(Command::Serve(config)) => serve(&config),
        Some(Command::Shade { file, budget }) => printed(
            offline::read(&file)
                .and_then(|body| budget.applied(body))
                .and_then(|body| offline::shade(&body)),
        ),
        Some(Command::Render(args)) => match &args.via {
            Some(via) => render_via(&args, via),
            None => printed(render(&args)),
        },
        Some(Command::Bake(args)) => printed(bake(&args)),
        Some(Command::Compare { request, candidate }) => compare(&request, &candidate),
        Some(Command::Healthcheck { url, timeout_ms }) => {
            healthcheck(url, Duration::from_millis(timeout_ms))
        }
    }
}

fn serve(config: &ServeConfig) -> ExitCode {
    match glint::http::run(config) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("glint: {e:#}");
            ExitCode::FAILURE
        }
    }
}

/// Prints a command's output (nothing when it went to a file), or its
/// problem+json on stderr with a failure exit code.
fn printed(result: Result<Vec<u8>, Problem>) -> ExitCode {
    match result {
        Ok(out) if out.is_empty() => ExitCode::SUCCESS,
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

/// `glint compare`: the summary on stdout and 0 within the bound, 1
/// outside it; a problem on stderr and 2.
fn compare(request: &Path, candidate: &Path) -> ExitCode {
    let compared = offline::read(request)
        .and_then(|request| offline::compare(&request, &offline::read(candidate)?));
    match compared {
        Ok(compared) => {
            print!("{}", compared.summary());
            ExitCode::from(u8::from(!compared.within_bound()))
        }
        Err(problem) => {
            eprintln!(
                "{}",
                serde_json::to_string(&problem).expect("a problem always serialises")
            );
            ExitCode::from(2)
        }
    }
}

/// Renders FILE (or its tile `--tile`): the PNG to `-o`, and with `--json`
/// the JSON form to stdout.
fn render(args: &RenderArgs) -> Result<Vec<u8>, Problem> {
    let mut body = args.budget.applied(offline::read(&args.file)?)?;
    if let Some(index) = args.tile {
        let plan = plan(&body, args.tiles)?;
        let tile = *plan
            .tiles
            .get(index)
            .ok_or_else(|| offline::no_such_tile(index, plan.tiles.len()))?;
        body = plan.body(tile);
    }
    if args.output.is_none() && !args.json {
        return Err(offline::no_output());
    }
    let model = args.model.as_deref().map(offline::read).transpose()?;
    let rendered = offline::render(&body, model.as_deref(), args.json)?;
    if let Some(path) = &args.output {
        offline::write(path, &rendered.png)?;
    }
    Ok(rendered.json.unwrap_or_default())
}

/// `body` cut into the tiles of `grid`, once validated.
fn plan(body: &[u8], grid: Grid) -> Result<Plan, Problem> {
    let area = offline::render_area(body)?;
    Plan::new(body, area, grid)
        .map_err(|why| Problem::new(glint::problem::ProblemKind::Malformed, why).at(""))
}

/// `glint bake MODEL.glb`: the baked model to `-o`, or the JSON answer to
/// stdout.
fn bake(args: &BakeArgs) -> Result<Vec<u8>, Problem> {
    let model = offline::read(&args.model)?;
    let request = match (&args.request, args.budget.max_abs_error) {
        (None, None) => None,
        (None, Some(_)) => Some(args.budget.applied(b"{}".to_vec())?),
        (Some(file), _) => Some(args.budget.applied(offline::read(file)?)?),
    };
    let baked = offline::bake(&model, request.as_deref(), args.json)?;
    match &args.output {
        Some(path) if !args.json => offline::write(path, &baked).map(|()| Vec::new()),
        _ => Ok(baked),
    }
}

/// `glint render FILE --via URL`: the tiles through the service, stitched.
fn render_via(args: &RenderArgs, via: &str) -> ExitCode {
    let output = args
        .output
        .as_deref()
        .expect("-o is required without --json");
    let body = offline::read(&args.file).and_then(|body| args.budget.applied(body));
    let plan = match body.and_then(|body| plan(&body, args.tiles)) {
        Ok(plan) => plan,
        Err(problem) => return printed(Err(problem)),
    };
    let options = fanout::Options {
        via: via.to_owned(),
        parallel: args.parallel,
        tries: args.tries,
        try_timeout: Duration::from_secs(args.try_timeout_secs),
        progress: true,
    };
    let rendered = client_runtime().and_then(|rt| {
        rt.block_on(fanout::render(plan, &options))
            .map_err(|e| match &e {
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
    if let Err(problem) = offline::write(output, &done.png) {
        return printed(Err(problem));
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
        glint_client::ready::local_url(port)
    });
    let checked =
        client_runtime().and_then(|rt| rt.block_on(glint_client::ready::check(&url, timeout)));
    match checked {
        Ok(()) => ExitCode::SUCCESS,
        Err(why) => {
            eprintln!("glint: {why}");
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
