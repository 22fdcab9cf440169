//! The `frond` command line: global options and logging; each command is in `frond::cli`.

use std::process::ExitCode;

use clap::Parser;
use frond::cli::Command;
use frond::cli::flags::with_flags;
use frond::cli::terminal::{SafeWriter, safe};

#[derive(Parser)]
#[command(
    name = "frond",
    version,
    about = "Animated billboard-cloud LOD chains for wind-animated trees"
)]
struct Cli {
    /// Log more (-v info, -vv debug); RUST_LOG overrides.
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

fn main() -> ExitCode {
    // Like other Unix tools, end quietly when the reader of our output goes away
    // (`frond inspect --json big.glb | head`): Rust ignores SIGPIPE, so `println!` would panic.
    // SAFETY: setting a signal's disposition to the default before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let level = match cli.verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        // Mesa's EGL probe logs a harmless DRI2 error before falling back to llvmpipe.
        .unwrap_or_else(|_| {
            tracing_subscriber::EnvFilter::new(format!("{level},wgpu_hal::gles::egl=off"))
        });
    // Plain text, every control character in a message made visible (names from the input
    // reach log lines): see frond::cli::terminal.
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(|| SafeWriter(std::io::stderr()))
        .with_ansi(false)
        .init();
    match cli.command.run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", safe(&with_flags(&format!("{e:#}"))));
            ExitCode::FAILURE
        }
    }
}
