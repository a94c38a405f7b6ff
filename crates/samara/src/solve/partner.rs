//! A long-lived partner thread for the two parts of a separator order: `join(a, b)` runs
//! `b` on the partner and `a` on the caller, the partner spinning between jobs (a hand-over
//! costs a cache-line round trip, not a thread wake-up) and parking after a while idle.
//! Part 1's work always goes to the same thread, so its blocks stay in that core's caches.

use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::{Arc, OnceLock};
use std::thread::{self, Thread};
use std::time::{Duration, Instant};

const IDLE: u32 = 0;
const POSTED: u32 = 1;
const DONE: u32 = 2;

/// How long the partner spins for the next job before it parks.
const SPIN: Duration = Duration::from_millis(2);

struct Slot {
    state: AtomicU32,
    parked: AtomicBool,
    panicked: AtomicBool,
    /// The posted job: a lifetime-erased pointer to a closure on the caller's stack, valid
    /// until `state` reads `DONE` (the caller waits for it).
    job: UnsafeCell<Option<*const (dyn Fn() + Sync)>>,
    thread: OnceLock<Thread>,
}

// SAFETY: `job` is written by the caller before the release store of POSTED and read by
// the partner after the acquire load of it; the caller does not touch it until DONE.
unsafe impl Sync for Slot {}
unsafe impl Send for Slot {}

pub struct Partner {
    slot: Arc<Slot>,
}

impl Partner {
    fn spawn() -> Self {
        let slot = Arc::new(Slot {
            state: AtomicU32::new(IDLE),
            parked: AtomicBool::new(false),
            panicked: AtomicBool::new(false),
            job: UnsafeCell::new(None),
            thread: OnceLock::new(),
        });
        let s = slot.clone();
        let handle = thread::Builder::new()
            .name("samara-partner".into())
            .spawn(move || run(&s))
            .expect("spawn the partner thread");
        let _ = slot.thread.set(handle.thread().clone());
        Self { slot }
    }

    /// Runs `a` here and `b` on the partner; returns when both are done.
    pub fn join<A: FnOnce() -> RA, RA, B: FnOnce() -> RB + Send, RB: Send>(
        &self,
        a: A,
        b: B,
    ) -> (RA, RB) {
        let b = std::sync::Mutex::new(Some(b));
        let out: std::sync::Mutex<Option<RB>> = std::sync::Mutex::new(None);
        let job = || {
            let f = b.lock().unwrap().take().unwrap();
            *out.lock().unwrap() = Some(f());
        };
        let job: &(dyn Fn() + Sync) = &job;
        // SAFETY: the pointer is used by the partner only until it stores DONE, and this
        // function does not return before it reads DONE.
        let job: *const (dyn Fn() + Sync) = unsafe { std::mem::transmute(job) };
        let s = &*self.slot;
        unsafe { *s.job.get() = Some(job) };
        s.state.store(POSTED, Ordering::Release);
        if s.parked.load(Ordering::Acquire) {
            s.thread.get().unwrap().unpark();
        }
        let ra = a();
        while s.state.load(Ordering::Acquire) != DONE {
            spin_pause();
        }
        s.state.store(IDLE, Ordering::Relaxed);
        if s.panicked.swap(false, Ordering::Relaxed) {
            panic!("the partner thread's job panicked");
        }
        let rb = out.into_inner().unwrap().unwrap();
        (ra, rb)
    }
}

/// Pins the calling thread to `cpu` (prototype: `SAMARA_PARTNER_CPU`, `SAMARA_MAIN_CPU`).
pub fn pin(cpu: usize) {
    // SAFETY: a zeroed cpu_set_t is valid; the call reads it.
    unsafe {
        let mut set: libc::cpu_set_t = std::mem::zeroed();
        libc::CPU_SET(cpu, &mut set);
        libc::sched_setaffinity(0, std::mem::size_of::<libc::cpu_set_t>(), &set);
    }
}

/// The pause of a spin-wait: `SAMARA_SPIN_PAUSE=0` spins without the PAUSE instruction
/// (a guest's PAUSE loops may exit to the hypervisor).
#[inline(always)]
fn spin_pause() {
    static PAUSE: OnceLock<bool> = OnceLock::new();
    if *PAUSE.get_or_init(|| std::env::var("SAMARA_SPIN_PAUSE").as_deref() != Ok("0")) {
        std::hint::spin_loop();
    }
}

fn run(s: &Slot) {
    if let Some(c) = std::env::var("SAMARA_PARTNER_CPU")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        pin(c);
    }
    loop {
        let mut since = Instant::now();
        let mut spins = 0u32;
        while s.state.load(Ordering::Acquire) != POSTED {
            spin_pause();
            spins += 1;
            if spins & 1023 == 0 && since.elapsed() > SPIN {
                s.parked.store(true, Ordering::Release);
                if s.state.load(Ordering::Acquire) != POSTED {
                    thread::park_timeout(Duration::from_millis(50));
                }
                s.parked.store(false, Ordering::Release);
                since = Instant::now();
            }
        }
        // SAFETY: posted before the release store of POSTED.
        let job = unsafe { (*s.job.get()).take().unwrap() };
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| unsafe { (*job)() }));
        if r.is_err() {
            s.panicked.store(true, Ordering::Relaxed);
        }
        s.state.store(DONE, Ordering::Release);
    }
}

/// The process's partner thread, when `SAMARA_PARTNER=1` (the prototype's switch).
pub fn partner() -> Option<&'static Partner> {
    static P: OnceLock<Option<Partner>> = OnceLock::new();
    P.get_or_init(|| {
        (std::env::var("SAMARA_PARTNER").as_deref() == Ok("1")).then(|| {
            let p = Partner::spawn();
            if let Some(c) = std::env::var("SAMARA_MAIN_CPU")
                .ok()
                .and_then(|v| v.parse().ok())
            {
                pin(c);
            }
            p
        })
    })
    .as_ref()
}

/// Runs `a` and `b`: on the partner when there is one, else one after the other.
#[inline]
pub fn join2<A: FnOnce() -> RA, RA, B: FnOnce() -> RB + Send, RB: Send>(a: A, b: B) -> (RA, RB) {
    match partner() {
        Some(p) => p.join(a, b),
        None => {
            let ra = a();
            (ra, b())
        }
    }
}
