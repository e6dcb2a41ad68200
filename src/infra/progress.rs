//! Progress and cancellation of long computations: the library reports, the binary draws.
//!
//! A long library function takes an [`Observer`] (in the spirit of argmin's observers): it
//! names each phase with its number of steps, reports finished steps, and asks whether to
//! stop. The library never prints; the command line draws the reports as bars on a terminal
//! ([`Bars`]) and says nothing otherwise. [`SILENT`] observes nothing (tests, batteries, the
//! inner computations of a larger one).

use std::io::IsTerminal;
use std::sync::Mutex;

/// What a long computation reports while it runs. Every method has a do-nothing default;
/// implementations must be cheap and thread-safe (steps finish on worker threads).
pub trait Observer: Sync {
    /// A phase begins: its name (`null bootstrap`, `profiles`, …) and its number of steps
    /// (`None`: unknown).
    fn phase(&self, _name: &str, _total: Option<u64>) {}
    /// `n` steps of the current phase were found done by an earlier run (a journal): counted
    /// without entering the rate the time estimate uses.
    fn resumed(&self, _n: u64) {}
    /// `n` more steps of the current phase are done.
    fn advance(&self, _n: u64) {}
    /// One line about a finished step (a battery set's outcome), for a log.
    fn note(&self, _line: &str) {}
    /// Whether the computation should stop as soon as it can; what it has finished is kept
    /// (journaled) and the function returns an interruption.
    fn cancelled(&self) -> bool {
        false
    }
}

/// The observer that observes nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {}

/// A shared [`Silent`] observer.
pub static SILENT: Silent = Silent;

/// What a long computation is given: the observer it reports to, and the journal it keeps
/// its finished work in and resumes from (`None`: nothing kept).
#[derive(Clone, Copy)]
pub struct Hooks<'a> {
    /// Told of the phases and steps; asked whether to stop.
    pub observer: &'a dyn Observer,
    /// Where finished work is journaled and read back.
    pub journal: Option<&'a crate::journal::Journal>,
}

impl Default for Hooks<'_> {
    fn default() -> Self {
        Hooks {
            observer: &SILENT,
            journal: None,
        }
    }
}

impl Hooks<'_> {
    /// A phase of `total` steps begins (see [`Observer::phase`]).
    pub fn phase(&self, name: &str, total: usize) {
        self.observer.phase(name, Some(total as u64));
    }

    /// One step of the current phase is done.
    pub fn step(&self) {
        self.observer.advance(1);
    }

    /// [`crate::Error::Interrupted`] when the observer asks to stop (what is journaled
    /// stays), naming `phase`.
    pub fn check(&self, phase: &str) -> crate::Result<()> {
        if self.observer.cancelled() {
            return Err(self.interrupted(phase));
        }
        Ok(())
    }

    /// The interruption during `phase`.
    pub fn interrupted(&self, phase: &str) -> crate::Error {
        crate::Error::Interrupted(match self.journal {
            Some(j) => format!(
                "stopped during the {phase}; the finished work is journaled in {}: rerun the same command into the same folder to resume",
                j.path().display()
            ),
            None => format!("stopped during the {phase}"),
        })
    }
}

/// Forwards everything to `inner` and asks to stop also once `stop` says so: the
/// `--stop-after` of the commands that resume (an interruption at a known point, for tests:
/// the command line stops once so many new records are journaled).
pub struct StopWhen<'a> {
    inner: &'a dyn Observer,
    stop: Box<dyn Fn() -> bool + Sync + 'a>,
}

impl<'a> StopWhen<'a> {
    /// `inner`, cancelled also when `stop()` is true.
    pub fn new(inner: &'a dyn Observer, stop: impl Fn() -> bool + Sync + 'a) -> Self {
        StopWhen {
            inner,
            stop: Box::new(stop),
        }
    }
}

impl Observer for StopWhen<'_> {
    fn phase(&self, name: &str, total: Option<u64>) {
        self.inner.phase(name, total)
    }
    fn resumed(&self, n: u64) {
        self.inner.resumed(n)
    }
    fn advance(&self, n: u64) {
        self.inner.advance(n)
    }
    fn note(&self, line: &str) {
        self.inner.note(line)
    }
    fn cancelled(&self) -> bool {
        (self.stop)() || self.inner.cancelled()
    }
}

/// The command line's observer: one indicatif bar per phase (phase name, count, rate, ETA),
/// drawn on stderr only when it is a terminal and not `quiet`; notes go above the bar on a
/// terminal and to stderr as plain lines otherwise (unless `quiet`).
pub struct Bars {
    draw: bool,
    quiet: bool,
    bar: Mutex<Option<indicatif::ProgressBar>>,
}

impl Bars {
    /// Bars on stderr if it is a terminal, unless `quiet`.
    pub fn new(quiet: bool) -> Bars {
        Bars {
            draw: !quiet && std::io::stderr().is_terminal(),
            quiet,
            bar: Mutex::new(None),
        }
    }

    /// Whether anything is drawn.
    pub fn drawn(&self) -> bool {
        self.draw
    }

    fn with_bar(&self, f: impl FnOnce(&indicatif::ProgressBar)) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).as_ref() {
            f(b)
        }
    }

    /// Remove the bar (the phases are over).
    pub fn clear(&self) {
        if let Some(b) = self.bar.lock().unwrap_or_else(|e| e.into_inner()).take() {
            b.finish_and_clear();
        }
    }
}

impl Drop for Bars {
    fn drop(&mut self) {
        self.clear();
    }
}

impl Observer for Bars {
    fn phase(&self, name: &str, total: Option<u64>) {
        if !self.draw {
            return;
        }
        let mut slot = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(b) = slot.take() {
            b.finish_and_clear();
        }
        let (bar, template) = match total {
            Some(n) => (
                indicatif::ProgressBar::new(n),
                "{elapsed_precise} {prefix}: [{bar:30}] {pos}/{len}  {per_sec}  ETA {eta}",
            ),
            None => (
                indicatif::ProgressBar::new_spinner(),
                "{elapsed_precise} {prefix}: {spinner}",
            ),
        };
        bar.set_style(
            indicatif::ProgressStyle::with_template(template)
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(name.to_string());
        bar.enable_steady_tick(std::time::Duration::from_millis(250));
        *slot = Some(bar);
    }
    fn resumed(&self, n: u64) {
        self.with_bar(|b| {
            b.inc(n);
            b.reset_eta();
        });
    }
    fn advance(&self, n: u64) {
        self.with_bar(|b| b.inc(n));
    }
    fn note(&self, line: &str) {
        if self.quiet {
            return;
        }
        let mut shown = false;
        self.with_bar(|b| {
            b.println(line);
            shown = true;
        });
        if !shown {
            eprintln!("{line}");
        }
    }
}

/// `observer`, asked to stop once `journal` holds `limit` new records (`--stop-after`).
pub fn stop_after<'a>(
    observer: &'a dyn Observer,
    journal: &'a crate::journal::Journal,
    limit: Option<usize>,
) -> StopWhen<'a> {
    StopWhen::new(observer, move || {
        limit.is_some_and(|k| journal.written() >= k as u64)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Records what it is told.
    #[derive(Default)]
    struct Log(Mutex<Vec<String>>);

    impl Observer for Log {
        fn phase(&self, name: &str, total: Option<u64>) {
            self.0.lock().unwrap().push(format!("{name} {total:?}"));
        }
        fn advance(&self, n: u64) {
            self.0.lock().unwrap().push(format!("+{n}"));
        }
    }

    #[test]
    fn stop_when_forwards_and_stops_on_its_condition() {
        let log = Log::default();
        let n = AtomicU64::new(0);
        let s = StopWhen::new(&log, || n.load(Ordering::SeqCst) >= 3);
        s.phase("a", Some(5));
        s.advance(2);
        assert!(!s.cancelled());
        n.store(3, Ordering::SeqCst);
        assert!(s.cancelled());
        assert_eq!(*log.0.lock().unwrap(), ["a Some(5)", "+2"]);
        assert!(!StopWhen::new(&SILENT, || false).cancelled());
    }

    #[test]
    fn bars_draw_nothing_when_quiet() {
        let b = Bars::new(true);
        assert!(!b.drawn());
        b.phase("x", Some(3));
        b.advance(1);
        assert!(b.bar.lock().unwrap().is_none());
    }
}
