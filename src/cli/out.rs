//! Standard output for the commands: `print!` and `println!` in the binary are these (see
//! `main.rs`), so that a reader closing the pipe early (`hgym envs | head -1`) ends the program
//! quietly with exit code 0 instead of a panic.

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
