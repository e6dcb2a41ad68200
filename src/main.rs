//! The `creepfit` binary: parse the command line, run the library, map errors to a one-line
//! `error:` message and a non-zero exit status.

use clap::Parser;

fn main() {
    // Piping into `head` closes stdout early: end quietly like other Unix tools instead of
    // panicking in println!.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = creepfit::cli::Cli::parse();
    if let Err(e) = creepfit::cli::run(cli).map_err(anyhow::Error::from) {
        let msg = format!("{e:#}").replace('\n', " ");
        eprintln!("error: {msg}");
        std::process::exit(1);
    }
}
