//! Standard output and error for the commands: `print!`, `println!`, `eprint!` and `eprintln!`
//! in the binary are these (see `main.rs`), so that a reader closing the pipe early (`hgym envs |
//! head -1`) ends the program quietly with exit code 0 instead of a panic, and so that under MPI
//! only rank 0 speaks (the others run the same command; `main` reports their errors itself).

use std::io::Write;

/// Writes `args` to standard output; on a closed pipe exits with 0, on another write error
/// with 1 after saying so on standard error. Under MPI only rank 0 prints.
pub fn write_out(args: std::fmt::Arguments) {
    if !hgym::flow::ranks::leader() {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: cannot write to standard output: {e}");
        std::process::exit(1);
    }
}

/// Writes `args` to standard error, on rank 0 only (a failed write to standard error has nowhere
/// to be reported and is dropped).
pub fn write_err(args: std::fmt::Arguments) {
    if hgym::flow::ranks::leader() {
        let _ = std::io::stderr().lock().write_fmt(args);
    }
}
