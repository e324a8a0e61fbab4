//! What a long run is doing, told to whoever shows it (a progress bar on a terminal).

/// One step of a run: `done` of `total` steps finished, and what runs now.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Progress<'a> {
    /// Steps finished.
    pub done: usize,
    /// Steps in all (as far as known when the run starts; the last may be skipped).
    pub total: usize,
    /// What runs now.
    pub what: &'a str,
}

/// Counts a run's steps and tells `report` of each as it starts.
pub(crate) struct Steps<'a> {
    done: usize,
    total: usize,
    report: &'a dyn Fn(Progress),
}

impl<'a> Steps<'a> {
    pub(crate) fn new(total: usize, report: &'a dyn Fn(Progress)) -> Self {
        Steps {
            done: 0,
            total,
            report,
        }
    }

    /// Steps started so far.
    pub(crate) fn done(&self) -> usize {
        self.done
    }

    /// The count of steps, once it is known better.
    pub(crate) fn set_total(&mut self, total: usize) {
        self.total = total;
    }

    /// The next step, `what`, starts (the one before it is done).
    pub(crate) fn start(&mut self, what: &str) {
        (self.report)(Progress {
            done: self.done.min(self.total),
            total: self.total,
            what,
        });
        self.done += 1;
    }
}
