//! The server's configuration: every setting is a flag of `glint serve` and a
//! `GLINT_…` environment variable (flags win), with the default a laptop user
//! wants.

use std::net::SocketAddr;
use std::time::Duration;

use clap::Args;

use glint_lighting::MAX_LIGHTS;
use glint_trace::MAX_SAMPLES;

use crate::logging::{LogConfig, LogFormat};
use crate::scene::Limits;

/// `glint serve`.
#[derive(Args, Clone, Debug)]
pub struct ServeConfig {
    /// Address and port to listen on (0.0.0.0:8080 in a container).
    #[arg(long, env = "GLINT_LISTEN", default_value = "127.0.0.1:8080")]
    pub listen: SocketAddr,

    /// Worker threads for lighting and rendering (0: one per core).
    #[arg(long, env = "GLINT_THREADS", default_value_t = 0)]
    pub threads: usize,

    /// Jobs computed at once (0: as many as worker threads).
    #[arg(long, env = "GLINT_MAX_JOBS", default_value_t = 0)]
    pub max_jobs: usize,

    /// Jobs that may wait for a turn; past that, requests get 503 at once.
    #[arg(long, env = "GLINT_QUEUE", default_value_t = 64)]
    pub queue: usize,

    /// Largest request body, in bytes (413 past it).
    #[arg(long, env = "GLINT_MAX_BODY_BYTES", default_value_t = 128 * 1024 * 1024)]
    pub max_body_bytes: usize,

    /// Most vertices in one /v1/shade request, or mesh vertices in one render (413 past it).
    #[arg(long, env = "GLINT_MAX_VERTICES", default_value_t = Limits::default().max_vertices)]
    pub max_vertices: usize,

    /// Most lights in one request, at most 64 (413 past it).
    #[arg(long, env = "GLINT_MAX_LIGHTS", default_value_t = Limits::default().max_lights,
          value_parser = clap::builder::TypedValueParser::map(
              clap::value_parser!(u16).range(0..=MAX_LIGHTS as i64), usize::from))]
    pub max_lights: usize,

    /// Most pixels (width × height) in one render (413 past it).
    #[arg(long, env = "GLINT_MAX_PIXELS", default_value_t = Limits::default().max_pixels)]
    pub max_pixels: u64,

    /// Most samples per pixel in one render, at most 64 (413 past it).
    #[arg(long, env = "GLINT_MAX_SAMPLES", default_value_t = Limits::default().max_samples,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_SAMPLES)))]
    pub max_samples: u32,

    /// Time a connection has to send a request's head, in milliseconds.
    #[arg(long, env = "GLINT_HEADER_TIMEOUT_MS", default_value_t = 10_000)]
    pub header_timeout_ms: u64,

    /// Time a client has to send its whole body, in milliseconds (408 past it).
    #[arg(long, env = "GLINT_BODY_TIMEOUT_MS", default_value_t = 10_000)]
    pub body_timeout_ms: u64,

    /// Time a request may wait for and use a worker, in milliseconds (503 past it).
    #[arg(long, env = "GLINT_REQUEST_TIMEOUT_MS", default_value_t = 30_000)]
    pub request_timeout_ms: u64,

    /// Seconds a refused client is asked to wait (the Retry-After header).
    #[arg(long, env = "GLINT_RETRY_AFTER_SECS", default_value_t = 1)]
    pub retry_after_secs: u64,

    /// On SIGTERM or Ctrl-C, time in-flight requests get to finish, in milliseconds.
    #[arg(long, env = "GLINT_SHUTDOWN_GRACE_MS", default_value_t = 10_000)]
    pub shutdown_grace_ms: u64,

    /// On SIGTERM or Ctrl-C, time /readyz answers 503 while new connections
    /// are still served, before the listener closes, in milliseconds: a load
    /// balancer's health checks then see the replica leave before it refuses
    /// connections.
    #[arg(long, env = "GLINT_DRAIN_MS", default_value_t = 0)]
    pub drain_ms: u64,

    /// This replica's name, sent in every response's `x-served-by` (default:
    /// the host name).
    #[arg(long, env = "GLINT_INSTANCE_ID")]
    pub instance_id: Option<String>,

    /// Origins allowed by CORS, comma-separated; `*` allows any. None: no CORS headers.
    #[arg(long, env = "GLINT_CORS_ORIGINS", value_delimiter = ',')]
    pub cors_origins: Vec<String>,

    /// Log format.
    #[arg(long, env = "GLINT_LOG_FORMAT", value_enum, default_value_t = LogFormat::Human)]
    pub log_format: LogFormat,

    /// Log lines held while the log's reader is slow; past that, new lines
    /// are dropped (and counted in /metrics), never waited for.
    #[arg(long, env = "GLINT_LOG_BUFFER_LINES", default_value_t = 16_384,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub log_buffer_lines: u32,

    /// Serve the playground, a page to try the lighting model in a browser, at `/` (false: 404).
    #[arg(long, env = "GLINT_PLAYGROUND", default_value_t = true, action = clap::ArgAction::Set,
          num_args = 0..=1, default_missing_value = "true")]
    pub playground: bool,
}

impl ServeConfig {
    /// The per-request limits of this configuration.
    pub fn limits(&self) -> Limits {
        Limits {
            max_vertices: self.max_vertices,
            max_lights: self.max_lights,
            max_pixels: self.max_pixels,
            max_samples: self.max_samples,
        }
    }

    pub fn header_timeout(&self) -> Duration {
        Duration::from_millis(self.header_timeout_ms)
    }

    pub fn body_timeout(&self) -> Duration {
        Duration::from_millis(self.body_timeout_ms)
    }

    pub fn request_timeout(&self) -> Duration {
        Duration::from_millis(self.request_timeout_ms)
    }

    pub fn shutdown_grace(&self) -> Duration {
        Duration::from_millis(self.shutdown_grace_ms)
    }

    pub fn drain(&self) -> Duration {
        Duration::from_millis(self.drain_ms)
    }

    /// The name in `x-served-by`: `--instance-id`, else the host name (a
    /// pod's name on Kubernetes, a container's id under Docker).
    pub fn instance_id(&self) -> String {
        self.instance_id.clone().unwrap_or_else(host_name)
    }

    pub fn logs(&self) -> LogConfig {
        LogConfig {
            format: self.log_format,
            buffer_lines: self.log_buffer_lines as usize,
        }
    }
}

impl Default for ServeConfig {
    /// The defaults of the flags, as `glint serve` with no flags and no
    /// environment would have them.
    fn default() -> Self {
        #[derive(clap::Parser)]
        struct Defaults {
            #[command(flatten)]
            config: ServeConfig,
        }
        <Defaults as clap::Parser>::parse_from(["glint"]).config
    }
}

/// The host name, as the kernel has it; `glint` where it cannot be read.
fn host_name() -> String {
    ["/proc/sys/kernel/hostname", "/etc/hostname"]
        .iter()
        .find_map(|file| std::fs::read_to_string(file).ok())
        .map(|name| name.trim().to_owned())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .filter(|name| !name.is_empty())
        .unwrap_or_else(|| "glint".to_owned())
}
