//! The command-line tests of `samara`, one module per file of this folder, compiled and
//! linked as one test binary (a test is named `file::test`, e.g.
//! `cargo test --release -p samara-cli --test suite cli::`).

mod common;

mod campbell_cli;
mod cli;
mod examples;
mod isa_cli;
mod modal_cli;
mod python_example;
mod robustness;
mod section_cli;
mod span_plot_cli;
mod vtk_cli;
