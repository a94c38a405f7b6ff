//! Results writers.
