//! The loop's progress: who hears each step as it starts, and each fit iteration within it.

use super::MAX_STEPS;
use crate::Progress;

/// Who hears the loop's steps as they start ([`Progress`]: the start's fit, each step of
/// [`MAX_STEPS`], the report at the end; a candidate tried on the test rows is told within
/// its step).
pub type ProgressFn<'a> = &'a (dyn Fn(Progress<'_>) + Sync);

pub(super) fn no_progress(_: Progress<'_>) {}

/// The loop's progress, remembered so that each fit iteration can tell it again with the
/// iterations done so far.
pub(super) struct Heartbeat<'p> {
    progress: ProgressFn<'p>,
    last: std::sync::Mutex<(usize, usize, String)>,
    iterations: std::sync::atomic::AtomicUsize,
}

impl<'p> Heartbeat<'p> {
    pub(super) fn new(progress: ProgressFn<'p>) -> Self {
        Heartbeat {
            progress,
            last: std::sync::Mutex::new((0, LOOP_STEPS, String::new())),
            iterations: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    /// Tell `p` and remember it.
    pub(super) fn tell(&self, p: Progress<'_>) {
        if let Ok(mut l) = self.last.lock() {
            *l = (p.done, p.total, p.what.to_string());
        }
        (self.progress)(p);
    }

    /// One more fit iteration: the last step told again, with the count.
    pub(super) fn beat(&self) {
        let n = self
            .iterations
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            + 1;
        let Ok(l) = self.last.lock() else { return };
        let what = format!("{} ({n} least-squares iterations so far)", l.2);
        (self.progress)(Progress {
            done: l.0,
            total: l.1,
            what: &what,
        });
    }
}

/// Steps of one run of the loop: the start's fit, at most [`MAX_STEPS`] steps, the report.
pub(super) const LOOP_STEPS: usize = MAX_STEPS + 2;

/// `progress` told that the loop's step `done` (of [`LOOP_STEPS`]) starts, doing `what`.
pub(super) fn tell(progress: ProgressFn<'_>, done: usize, what: &str) {
    progress(Progress {
        done,
        total: LOOP_STEPS,
        what,
    });
}
