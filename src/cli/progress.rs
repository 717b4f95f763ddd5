//! Progress of a long run, for a person at a terminal and for a log file alike.
//!
//! On a terminal it is an indicatif bar. When stderr is redirected (CI, `nohup`, `make nightly`)
//! a bar is hidden, and a 40-minute validation would print nothing until it ends; there the same
//! calls print one plain line per tenth of the work: how far, how long so far, how long to go.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};

/// An indicatif bar on a terminal (hidden otherwise), labelled `label`, over `total` steps.
pub fn progress_bar(total: u64, label: &str) -> ProgressBar {
    if !std::io::stderr().is_terminal() || !hgym::flow::ranks::leader() {
        return ProgressBar::hidden();
    }
    styled_bar(total, label, "steps")
}

fn styled_bar(total: u64, label: &str, unit: &str) -> ProgressBar {
    let pb = ProgressBar::new(total);
    let template = format!("{{msg:>16}} [{{bar:40.cyan/blue}}] {{pos}}/{{len}} {unit}, {{per_sec}}, eta {{eta}}");
    let style = ProgressStyle::with_template(&template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    pb.set_style(style);
    pb.set_message(label.to_string());
    pb
}

/// A bar on a terminal; a line per tenth of `total` on stderr when it is not one.
pub struct Progress {
    bar: ProgressBar,
    log: Option<TenthsLog>,
}

impl Progress {
    /// Progress over `total` solver steps.
    pub fn new(total: u64, label: &str) -> Self {
        Self::counting(total, label, "steps")
    }

    /// Progress over `total` things called `unit` (`actions`, `files`).
    pub fn counting(total: u64, label: &str, unit: &str) -> Self {
        if !hgym::flow::ranks::leader() {
            // Under MPI rank 0 reports for every rank.
            return Progress {
                bar: ProgressBar::hidden(),
                log: None,
            };
        }
        if std::io::stderr().is_terminal() {
            Progress {
                bar: styled_bar(total, label, unit),
                log: None,
            }
        } else {
            Progress {
                bar: ProgressBar::hidden(),
                log: Some(TenthsLog::new(total, label, unit)),
            }
        }
    }

    /// `done` of the `total` steps are finished.
    pub fn set_position(&self, done: u64) {
        self.bar.set_position(done);
        if let Some(line) = self.log.as_ref().and_then(|log| log.line(done)) {
            eprintln!("{line}");
        }
    }

    pub fn finish_and_clear(&self) {
        self.bar.finish_and_clear();
    }
}

/// Shows a first reset's spin-up (an observer for [`hgym::env::spin_up`]): one bar or log at a
/// time; reports of a spin-up that starts while another is shown are left out. A spin-up that
/// stopped early (`total == 0`) is cleared without a line: its error follows.
pub fn spin_up_progress(serial: u64, id: &str, done: u64, total: u64) {
    static SHOWN: Mutex<Option<(u64, Progress)>> = Mutex::new(None);
    let Ok(mut shown) = SHOWN.lock() else {
        return;
    };
    if done == 0 && shown.is_none() {
        *shown = Some((serial, Progress::new(total, &format!("spin-up of {id}"))));
    }
    if let Some((s, pb)) = shown.as_ref() {
        if *s == serial {
            if total > 0 {
                pb.set_position(done);
            }
            if done >= total {
                pb.finish_and_clear();
                *shown = None;
            }
        }
    }
}

/// The plain-text reports: which tenth comes next, and the clock they are timed by.
struct TenthsLog {
    label: String,
    unit: String,
    total: u64,
    next_tenth: AtomicU64,
    start: Instant,
}

impl TenthsLog {
    fn new(total: u64, label: &str, unit: &str) -> Self {
        TenthsLog {
            label: label.to_string(),
            unit: unit.to_string(),
            total,
            next_tenth: AtomicU64::new(1),
            start: Instant::now(),
        }
    }

    /// The line to print when `done` reaches a tenth not yet reported (only the highest one when
    /// several are passed at once), or nothing.
    fn line(&self, done: u64) -> Option<String> {
        if self.total == 0 {
            return None;
        }
        let done = done.min(self.total);
        let tenth = done.saturating_mul(10) / self.total;
        if tenth < self.next_tenth.fetch_max(tenth + 1, Ordering::Relaxed) {
            return None;
        }
        let elapsed = self.start.elapsed().as_secs_f64();
        if done == self.total {
            return Some(format!("{}: 100% ({done} {}) in {}", self.label, self.unit, duration(elapsed)));
        }
        let left = elapsed * (self.total - done) as f64 / done as f64;
        Some(format!(
            "{}: {}% ({done} of {} {}), {} so far, about {} to go",
            self.label,
            10 * tenth,
            self.total,
            self.unit,
            duration(elapsed),
            duration(left)
        ))
    }
}

/// `s` seconds as "42 s", "7 min 05 s" or "1 h 03 min".
fn duration(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    match s {
        0..=59 => format!("{s} s"),
        60..=3599 => format!("{} min {:02} s", s / 60, s % 60),
        _ => format!("{} h {:02} min", s / 3600, (s % 3600) / 60),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_line_per_tenth_and_none_twice() {
        let log = TenthsLog::new(1000, "case", "steps");
        assert!(log.line(0).is_none());
        assert!(log.line(99).is_none());
        let first = log.line(100).expect("10 % is reported");
        assert!(first.starts_with("case: 10% (100 of 1000 steps)"), "{first}");
        assert!(log.line(150).is_none(), "10 % is not reported twice");
        // Jumping over several tenths reports only the highest.
        assert!(log.line(730).expect("70 %").starts_with("case: 70% (730 of 1000"));
        assert!(log.line(750).is_none());
        assert!(log.line(1000).expect("100 %").starts_with("case: 100% (1000 steps) in "));
        assert!(log.line(1000).is_none());
        assert!(TenthsLog::new(0, "empty", "steps").line(0).is_none());
    }

    #[test]
    fn durations_read_as_people_write_them() {
        assert_eq!(duration(42.4), "42 s");
        assert_eq!(duration(425.0), "7 min 05 s");
        assert_eq!(duration(3780.0), "1 h 03 min");
    }
}
