//! `glint`: the service, and the same engine offline on a scene file.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use base64::Engine;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use glint::config::{LogFormat, ServeConfig};
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
    /// Render a /v1/render request from FILE (`-` for stdin) to a PNG.
    Render {
        file: PathBuf,
        /// Where to write the PNG (required unless --json).
        #[arg(short, long, required_unless_present = "json")]
        output: Option<PathBuf>,
        /// Print the JSON form of the response instead (with -o, the PNG is
        /// written as well).
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        None => serve(&cli.serve),
        Some(Command::Serve(config)) => serve(&config),
        Some(Command::Shade { file }) => offline(shade(&file)),
        Some(Command::Render { file, output, json }) => {
            match render(&file, output.as_deref(), json) {
                // The PNG went to its file: nothing to print.
                Ok(out) if out.is_empty() => ExitCode::SUCCESS,
                result => offline(result),
            }
        }
    }
}

fn serve(config: &ServeConfig) -> ExitCode {
    init_logging(config.log_format);
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

fn init_logging(format: LogFormat) {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let builder = tracing_subscriber::fmt().with_env_filter(filter);
    match format {
        LogFormat::Human => builder.init(),
        LogFormat::Json => builder.json().init(),
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
    let response = shade::shade(&scene);
    Ok(serde_json::to_vec(&response).expect("a response always serialises"))
}

/// Renders FILE: the PNG to `output`, and with `json` the JSON form to
/// stdout. Prints nothing else on success.
fn render(file: &PathBuf, output: Option<&Path>, json: bool) -> Result<Vec<u8>, Problem> {
    let body = read_input(file)?;
    let scene = scene::parse_render(&body, &Limits::default()).map_err(Problem::from)?;
    let write_png = |png: &[u8], path: &Path| {
        std::fs::write(path, png)
            .map_err(|e| Problem::new(ProblemKind::Unwritable, format!("{}: {e}", path.display())))
    };
    match (output, json) {
        (None, false) => Err(Problem::new(
            ProblemKind::NoOutput,
            "give -o OUT.png, or --json to print the JSON form",
        )),
        (Some(path), false) => {
            write_png(&render::render_png(&scene), path)?;
            Ok(Vec::new())
        }
        (output, true) => {
            let response = render::render_json(&scene, &|| false).expect("never cancelled");
            if let Some(path) = output {
                let png = base64::engine::general_purpose::STANDARD
                    .decode(&response.png_base64)
                    .expect("our own base64");
                write_png(&png, path)?;
            }
            Ok(serde_json::to_vec(&response).expect("a response always serialises"))
        }
    }
}
