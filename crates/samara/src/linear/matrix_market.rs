//! Matrix Market coordinate files (`%%MatrixMarket matrix coordinate real general`,
//! 1-based indices; NIST format, readable by scipy.io.mmread, MATLAB, Julia).

use faer::sparse::SparseColMat;
use std::io::Write;

/// Writes `a` in Matrix Market coordinate format; `comment` lines are prefixed with `%`.
pub fn write(
    out: &mut impl Write,
    a: &SparseColMat<usize, f64>,
    comment: &[String],
) -> std::io::Result<()> {
    let r = a.as_ref();
    writeln!(out, "%%MatrixMarket matrix coordinate real general")?;
    for c in comment {
        for line in c.lines() {
            writeln!(out, "% {line}")?;
        }
    }
    writeln!(out, "{} {} {}", a.nrows(), a.ncols(), r.compute_nnz())?;
    for j in 0..a.ncols() {
        for (&i, &v) in r.row_idx_of_col_raw(j).iter().zip(r.val_of_col(j)) {
            writeln!(out, "{} {} {:e}", i + 1, j + 1, v)?;
        }
    }
    Ok(())
}

/// Reads a Matrix Market coordinate real file (general; symmetric expanded). For tests
/// and users reading back what [`write`] wrote.
pub fn read(text: &str) -> Result<SparseColMat<usize, f64>, String> {
    let mut lines = text.lines();
    let header = lines.next().ok_or("empty file")?.to_ascii_lowercase();
    if !header.starts_with("%%matrixmarket matrix coordinate real") {
        return Err(format!("unsupported header '{header}'"));
    }
    let symmetric = header.contains("symmetric");
    let mut lines = lines.filter(|l| !l.starts_with('%') && !l.trim().is_empty());
    let size = lines.next().ok_or("missing size line")?;
    let dims: Vec<usize> = size
        .split_whitespace()
        .map(|s| s.parse::<usize>().map_err(|e| format!("size line: {e}")))
        .collect::<Result<_, _>>()?;
    let [nr, nc, nnz] = dims[..] else {
        return Err("size line needs rows, columns, entries".into());
    };
    let mut t = Vec::with_capacity(nnz);
    for line in lines {
        let mut it = line.split_whitespace();
        let mut field = || it.next().ok_or_else(|| format!("short line '{line}'"));
        let i: usize = field()?.parse().map_err(|e| format!("{line}: {e}"))?;
        let j: usize = field()?.parse().map_err(|e| format!("{line}: {e}"))?;
        let v: f64 = field()?.parse().map_err(|e| format!("{line}: {e}"))?;
        if i == 0 || j == 0 || i > nr || j > nc {
            return Err(format!("index out of range in '{line}'"));
        }
        t.push(faer::sparse::Triplet::new(i - 1, j - 1, v));
        if symmetric && i != j {
            t.push(faer::sparse::Triplet::new(j - 1, i - 1, v));
        }
    }
    SparseColMat::try_new_from_triplets(nr, nc, &t).map_err(|e| format!("{e:?}"))
}
