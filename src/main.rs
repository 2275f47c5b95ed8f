//! `glint`: the service, and the same engine offline on a scene file.

use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use glint::config::{LogFormat, ServeConfig};
use glint::problem::Problem;
use glint::scene::{self, Limits};
use glint::shading;

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
    },
    /// Render a /v1/render request from FILE (`-` for stdin) to a PNG.
    Render {
        file: PathBuf,
        /// Where to write the PNG.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print the JSON form of the response instead.
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
        Some(Command::Render { .. }) => offline(Err(Problem::new(
            501,
            "not-implemented",
            "Not implemented",
            "this build of glint does not render images yet",
        ))),
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
    read.map_err(|e| {
        Problem::new(
            400,
            "unreadable",
            "Cannot read the request",
            format!("{}: {e}", file.display()),
        )
    })?;
    Ok(bytes)
}

fn shade(file: &PathBuf) -> Result<Vec<u8>, Problem> {
    let body = read_input(file)?;
    let scene = scene::parse_shade(&body, &Limits::default()).map_err(|e| Problem::from(&e))?;
    let response = shading::shade(&scene);
    Ok(serde_json::to_vec(&response).expect("a response always serialises"))
}
