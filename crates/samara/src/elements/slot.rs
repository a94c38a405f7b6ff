//! An f64 an element keeps between evaluations (a solver's warm start, the power at the
//! last residual evaluation), shared between threads: its bits in an atomic, NaN for none.

use std::sync::atomic::{AtomicU64, Ordering};

/// A kept f64 (NaN: none yet); `get` gives only finite values.
#[derive(Debug)]
pub(crate) struct Slot(AtomicU64);

impl Slot {
    pub(crate) fn new() -> Self {
        Self(AtomicU64::new(f64::NAN.to_bits()))
    }
    pub(crate) fn get(&self) -> Option<f64> {
        Some(f64::from_bits(self.0.load(Ordering::Relaxed))).filter(|x| x.is_finite())
    }
    pub(crate) fn set(&self, value: f64) {
        self.0.store(value.to_bits(), Ordering::Relaxed);
    }
    pub(crate) fn clear(&self) {
        self.set(f64::NAN);
    }
}

impl Clone for Slot {
    fn clone(&self) -> Self {
        Self(AtomicU64::new(self.0.load(Ordering::Relaxed)))
    }
}
