//! A long-lived partner thread for the two parts of a separator order: `join(a, b)` runs
//! `b` on the partner and `a` on the caller, the partner spinning between jobs (a hand-over
//! costs a cache-line round trip, not a thread wake-up) and parking after a while idle.
//! Part 1's work always goes to the same thread, so its blocks stay in that core's caches.
//!
//! A run owns its partner ([`Partner::spawn`]; dropped, the thread ends) and makes it the
//! current one of its thread for a step ([`within`]); [`join2`] then hands part 1 to it,
//! and without one runs both parts here, one after the other (the same operations in the
//! same order: the results do not depend on whether there is a partner).

use std::cell::{Cell, UnsafeCell};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, OnceLock};
use std::thread::{self, JoinHandle, Thread};
use std::time::{Duration, Instant};

const IDLE: u32 = 0;
const POSTED: u32 = 1;
const DONE: u32 = 2;

/// How long the partner waits for the next job before it parks.
const SPIN: Duration = Duration::from_millis(2);

/// Spins (`pause`, ~37 ns each on the 2-core EPYC host) a wait may take before it yields
/// the core at every turn: the budget adapts between these bounds, doubling after a wait
/// that ended within it and halving after one that had to yield. On a quiet machine the
/// waits (a few to tens of µs) end within ~300 µs of spinning and never yield; on a busy
/// one (more runnable threads than cores, as when two-part runs go side by side) a thread
/// that kept spinning took the core from the one it waited for: two such runs on two cores
/// took 6.6–16 s instead of 0.48 s.
const MIN_SPINS: u32 = 64;
const MAX_SPINS: u32 = 8192;

/// Waits until `done()`: spins up to `budget`, then yields the core at every turn; adapts
/// the budget (see [`MAX_SPINS`]).
#[inline]
fn wait_for(budget: &mut u32, done: impl Fn() -> bool) {
    let mut spins = 0u32;
    while !done() {
        if spins < *budget {
            spins += 1;
            std::hint::spin_loop();
        } else {
            spins = u32::MAX;
            thread::yield_now();
        }
    }
    *budget = if spins == u32::MAX {
        (*budget / 2).max(MIN_SPINS)
    } else {
        (*budget * 2).min(MAX_SPINS)
    };
}

type Job = *const (dyn Fn() + 'static);

struct Slot {
    state: AtomicU32,
    parked: AtomicBool,
    panicked: AtomicBool,
    stop: AtomicBool,
    /// The caller's spin budget ([`wait_for`]; only the caller touches it).
    budget: AtomicU32,
    /// The posted job: a lifetime-erased pointer to a closure on the caller's stack, valid
    /// until `state` reads `DONE` (the caller waits for it).
    job: UnsafeCell<Option<Job>>,
    thread: OnceLock<Thread>,
}

// SAFETY: `job` is written by the caller before the release store of POSTED and read by
// the partner after the acquire load of it; the caller does not touch it until DONE.
unsafe impl Sync for Slot {}
// SAFETY: as above.
unsafe impl Send for Slot {}

/// The partner thread of a run.
pub struct Partner {
    slot: Arc<Slot>,
    handle: Option<JoinHandle<()>>,
}

impl Partner {
    /// Starts the thread.
    pub fn spawn() -> std::io::Result<Self> {
        let slot = Arc::new(Slot {
            state: AtomicU32::new(IDLE),
            parked: AtomicBool::new(false),
            panicked: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            budget: AtomicU32::new(MAX_SPINS),
            job: UnsafeCell::new(None),
            thread: OnceLock::new(),
        });
        let s = slot.clone();
        let handle = thread::Builder::new()
            .name("samara-partner".into())
            .spawn(move || run(&s))?;
        let _ = slot.thread.set(handle.thread().clone());
        Ok(Self {
            slot,
            handle: Some(handle),
        })
    }

    fn wake(&self) {
        if self.slot.parked.load(Ordering::Acquire)
            && let Some(t) = self.slot.thread.get()
        {
            t.unpark();
        }
    }

    /// Runs `a` here and `b` on the partner; returns when both are done. A panic of `b` is
    /// raised here.
    pub fn join<A: FnOnce() -> RA, RA, B: FnOnce() -> RB + Send, RB: Send>(
        &self,
        a: A,
        b: B,
    ) -> (RA, RB) {
        let b = UnsafeCell::new(Some(b));
        let out: UnsafeCell<Option<RB>> = UnsafeCell::new(None);
        let job = || {
            // SAFETY: the partner is the only one touching `b` and `out` until DONE.
            unsafe {
                let f = (*b.get()).take().expect("a job runs once");
                *out.get() = Some(f());
            }
        };
        let job: *const (dyn Fn() + '_) = &job;
        // SAFETY: the pointer is used by the partner only until it stores DONE, and this
        // function does not return (nor unwind) before it reads DONE.
        let job: Job = unsafe { std::mem::transmute::<*const (dyn Fn() + '_), Job>(job) };
        let s = &*self.slot;
        // SAFETY: IDLE: the partner does not read `job`.
        unsafe { *s.job.get() = Some(job) };
        s.state.store(POSTED, Ordering::Release);
        self.wake();
        let ra = std::panic::catch_unwind(std::panic::AssertUnwindSafe(a));
        let mut budget = s.budget.load(Ordering::Relaxed);
        wait_for(&mut budget, || s.state.load(Ordering::Acquire) == DONE);
        s.budget.store(budget, Ordering::Relaxed);
        s.state.store(IDLE, Ordering::Relaxed);
        let ra = match ra {
            Ok(r) => r,
            Err(e) => std::panic::resume_unwind(e),
        };
        if s.panicked.swap(false, Ordering::Relaxed) {
            panic!("the partner thread's part of the step panicked");
        }
        (ra, out.into_inner().expect("the job ran"))
    }
}

impl Drop for Partner {
    fn drop(&mut self) {
        self.slot.stop.store(true, Ordering::Release);
        if let Some(t) = self.slot.thread.get() {
            t.unpark();
        }
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn run(s: &Slot) {
    let mut budget = MAX_SPINS;
    loop {
        // Spin up to the budget, then yield at every turn, and park once idle for SPIN
        // (the budget adapts as the caller's does, see `MAX_SPINS`).
        let mut since = Instant::now();
        let mut spins = 0u32;
        while s.state.load(Ordering::Acquire) != POSTED {
            if s.stop.load(Ordering::Acquire) {
                return;
            }
            if spins < budget {
                spins += 1;
                std::hint::spin_loop();
                continue;
            }
            spins = u32::MAX;
            if since.elapsed() > SPIN {
                s.parked.store(true, Ordering::Release);
                if s.state.load(Ordering::Acquire) != POSTED && !s.stop.load(Ordering::Acquire) {
                    thread::park_timeout(Duration::from_millis(50));
                }
                s.parked.store(false, Ordering::Release);
                since = Instant::now();
            } else {
                thread::yield_now();
            }
        }
        budget = if spins == u32::MAX {
            (budget / 2).max(MIN_SPINS)
        } else {
            (budget * 2).min(MAX_SPINS)
        };
        // SAFETY: posted before the release store of POSTED.
        let job = unsafe { (*s.job.get()).take() };
        if let Some(job) = job {
            // SAFETY: the caller keeps the closure alive until DONE.
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| unsafe { (*job)() }));
            if r.is_err() {
                s.panicked.store(true, Ordering::Relaxed);
            }
        }
        s.state.store(DONE, Ordering::Release);
    }
}

thread_local! {
    /// The partner of the step running on this thread ([`within`]).
    static CURRENT: Cell<*const Partner> = const { Cell::new(std::ptr::null()) };
}

/// Runs `f` with `p` as this thread's partner (none: both parts here).
pub fn within<R>(p: Option<&Partner>, f: impl FnOnce() -> R) -> R {
    struct Restore(*const Partner);
    impl Drop for Restore {
        fn drop(&mut self) {
            CURRENT.with(|c| c.set(self.0));
        }
    }
    let new = p.map_or(std::ptr::null(), |p| p as *const Partner);
    let _restore = Restore(CURRENT.with(|c| c.replace(new)));
    f()
}

/// Whether this thread has a partner for its step.
pub fn active() -> bool {
    CURRENT.with(|c| !c.get().is_null())
}

/// Runs `a` and `b`: `b` on this thread's partner when it has one, else one after the
/// other here.
#[inline]
pub fn join2<A: FnOnce() -> RA, RA, B: FnOnce() -> RB + Send, RB: Send>(a: A, b: B) -> (RA, RB) {
    let p = CURRENT.with(|c| c.get());
    if p.is_null() {
        let ra = a();
        (ra, b())
    } else {
        // SAFETY: set by `within`, whose borrow of the partner outlives this call.
        unsafe { &*p }.join(a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    #[test]
    fn join_runs_the_second_part_on_the_partner_and_returns_both() {
        let p = Partner::spawn().unwrap();
        let here = thread::current().id();
        for k in 0..100 {
            let (a, (b, id)) = p.join(|| k + 1, || (2 * k, thread::current().id()));
            assert_eq!((a, b), (k + 1, 2 * k));
            assert_ne!(id, here);
        }
    }

    #[test]
    fn a_parked_partner_wakes_for_the_next_job() {
        let p = Partner::spawn().unwrap();
        p.join(|| (), || ());
        // Idle longer than SPIN, it parks (waited for up to 5 s on a loaded machine).
        let t = Instant::now();
        while !p.slot.parked.load(Ordering::Acquire) && t.elapsed() < Duration::from_secs(5) {
            thread::sleep(SPIN);
        }
        assert!(p.slot.parked.load(Ordering::Acquire), "parked when idle");
        let n = AtomicUsize::new(0);
        p.join(
            || n.fetch_add(1, Ordering::Relaxed),
            || n.fetch_add(1, Ordering::Relaxed),
        );
        assert_eq!(n.load(Ordering::Relaxed), 2);
    }

    #[test]
    fn a_panic_in_either_part_is_raised_here_once_both_are_done() {
        let p = Partner::spawn().unwrap();
        let done = AtomicBool::new(false);
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            p.join(
                || done.store(true, Ordering::Relaxed),
                || panic!("part 1 failed"),
            )
        }));
        let e = r.expect_err("part 1's panic raised on the caller");
        let msg = e.downcast_ref::<&str>().copied().unwrap_or_default();
        assert!(msg.contains("partner thread"), "{msg}");
        assert!(done.load(Ordering::Relaxed), "part 0 ran to its end");
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            p.join(
                || panic!("part 0 failed"),
                || {
                    thread::sleep(Duration::from_millis(5));
                    done.store(false, Ordering::Relaxed)
                },
            )
        }));
        assert!(r.is_err(), "part 0's panic raised");
        assert!(
            !done.load(Ordering::Relaxed),
            "part 1 finished before the unwind"
        );
        // The partner still serves jobs after both panics.
        assert_eq!(p.join(|| 1, || 2), (1, 2));
    }

    #[test]
    fn join2_uses_the_current_partner_only_within() {
        let here = thread::current().id();
        let (_, id) = join2(|| (), || thread::current().id());
        assert_eq!(id, here, "no partner: both parts here");
        assert!(!active());
        let p = Partner::spawn().unwrap();
        within(Some(&p), || {
            assert!(active());
            let (_, id) = join2(|| (), || thread::current().id());
            assert_ne!(id, here, "part 1 on the partner");
        });
        assert!(!active(), "restored after `within`");
    }
}
