//! `section = "file.section.toml"` in `[[beams.sections]]`: every named section file is
//! solved by the cross-sectional analysis (in parallel, one station per file) or taken
//! from the cache, and its stiffness and mass stand in for the station's matrices before
//! the model is validated.
//!
//! The cache (if the caller gives one) holds each solved section as
//! `<cache dir>/<content hash>.toml`; `samara run` keeps it in `<results dir>/sections/`
//! and writes it, `samara check` only reads it (docs/sections.md).

use super::ModelInput;
use super::error::{Diagnostic, SourceFile};
use crate::section::results::{Cache, Solved, solve_cached};
use nalgebra::Matrix6;
use std::path::{Path, PathBuf};

/// Options of model loading.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Where solved sections are cached (none: solve every time, write nothing).
    pub section_cache: Option<Cache>,
}

/// Resolves every `section = …` of the beams' sections in place; returns the errors, each
/// located at its `section` value.
pub fn resolve(
    input: &mut ModelInput,
    source: &SourceFile,
    options: &LoadOptions,
) -> Vec<Diagnostic> {
    let base = source.path.parent().unwrap_or(Path::new(".")).to_path_buf();
    // Unique files in order of appearance.
    let mut files: Vec<PathBuf> = Vec::new();
    let mut diags = Vec::new();
    for b in &input.beams {
        for s in &b.value.sections {
            let si = &s.value;
            if let Some(f) = &si.section {
                if si.stiffness.is_some() || si.mass.is_some() || si.isotropic.is_some() {
                    diags.push(
                        Diagnostic::error(
                            format!(
                                "beam '{}', section at station {}: `section` computes the stiffness and mass; do not give `stiffness`, `mass` or `isotropic` as well",
                                b.value.name.value, si.station
                            ),
                            f.span.clone(),
                        )
                        .with_hint("keep either the section file or the matrices"),
                    );
                    continue;
                }
                let p = base.join(&f.value);
                if !files.contains(&p) {
                    files.push(p);
                }
            }
        }
    }
    if files.is_empty() {
        return diags;
    }
    let cache = options.section_cache.as_ref();
    let solved: Vec<Result<Solved, Vec<super::ModelError>>> = {
        use rayon::prelude::*;
        files.par_iter().map(|p| solve_cached(p, cache)).collect()
    };
    for b in &mut input.beams {
        let beam = b.value.name.value.clone();
        for s in &mut b.value.sections {
            let si = &mut s.value;
            let Some(f) = si.section.clone() else {
                continue;
            };
            if si.stiffness.is_some() || si.mass.is_some() || si.isotropic.is_some() {
                continue;
            }
            let p = base.join(&f.value);
            let k = files.iter().position(|q| *q == p).expect("listed");
            match &solved[k] {
                Ok(r) => {
                    let arr = |m: &Matrix6<f64>| -> [[f64; 6]; 6] {
                        std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
                    };
                    si.stiffness = Some(arr(&r.stiffness));
                    si.mass = Some(arr(&r.mass));
                }
                Err(errors) => {
                    let mut detail = String::new();
                    for e in errors {
                        detail.push_str(e.render_plain().trim_end());
                        detail.push('\n');
                    }
                    diags.push(
                        Diagnostic::error(
                            format!(
                                "beam '{beam}', section at station {}: the section file '{}' cannot be used:\n{}",
                                si.station,
                                p.display(),
                                detail.trim_end()
                            ),
                            f.span.clone(),
                        )
                        .with_hint("the path is relative to the model file; `samara section FILE` checks a section file on its own"),
                    );
                }
            }
        }
    }
    diags
}
