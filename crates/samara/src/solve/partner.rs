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

/// How long the partner spins for the next job before it parks.
const SPIN: Duration = Duration::from_millis(2);

type Job = *const (dyn Fn() + 'static);

struct Slot {
    state: AtomicU32,
    parked: AtomicBool,
    panicked: AtomicBool,
    stop: AtomicBool,
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
        while s.state.load(Ordering::Acquire) != DONE {
            std::hint::spin_loop();
        }
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
    loop {
        let mut since = Instant::now();
        let mut spins = 0u32;
        while s.state.load(Ordering::Acquire) != POSTED {
            if s.stop.load(Ordering::Acquire) {
                return;
            }
            std::hint::spin_loop();
            spins = spins.wrapping_add(1);
            if spins & 1023 == 0 && since.elapsed() > SPIN {
                s.parked.store(true, Ordering::Release);
                if s.state.load(Ordering::Acquire) != POSTED && !s.stop.load(Ordering::Acquire) {
                    thread::park_timeout(Duration::from_millis(50));
                }
                s.parked.store(false, Ordering::Release);
                since = Instant::now();
            }
        }
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
