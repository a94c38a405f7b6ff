//! Block-sparse matrices with a structurally symmetric block pattern.
//!
//! The matrix is partitioned into square diagonal blocks (`sizes[k]` rows and
//! columns for block `k`). Each present block `(i, j)` is stored densely in
//! row-major order (`sizes[i] x sizes[j]`) in one flat `values` vector. The
//! block pattern is always structurally symmetric: a coupling `(i, j)` creates
//! both `(i, j)` and `(j, i)`, and all diagonal blocks are present.

use std::sync::Arc;

/// Role of a diagonal block in a constrained multibody system.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockKind {
    /// Primary unknowns (e.g. a node with 6 dofs).
    Primary,
    /// Lagrange multipliers of constraint equations: eliminated after every primary they
    /// couple (their pivot `−B M⁻¹ Bᵀ` then has all of `B`'s columns).
    Multiplier,
    /// Multipliers of a relative constraint ([`crate::core::Constraint::is_relative`])
    /// coupled to its nodes only: its rows restricted to either node's columns have the
    /// rank of all of them, so the block may be eliminated right after a node whose only
    /// multiplier it is ([`super::BlockLuSymbolic`]'s minimum-fill order). A chain is then
    /// factored from its tip, body and joint in turn, with no fill between joints.
    RelativeMultiplier,
    /// Projection multipliers η of the stabilized index-2 formulation: eliminated after
    /// every primary they couple, like [`Self::Multiplier`], but their columns are zero in
    /// every row that is not a projection's (the couplings of `Bᵀη` into the other rows are
    /// left out of the matrix), so the Schur updates through them never reach a primary's
    /// or another multiplier's pivot: they do not keep a relative constraint's multipliers
    /// from going right after a node.
    Projection,
}

impl BlockKind {
    /// Lagrange multipliers of any kind.
    #[inline]
    pub fn is_multiplier(self) -> bool {
        matches!(
            self,
            Self::Multiplier | Self::RelativeMultiplier | Self::Projection
        )
    }
}

/// Error raised when a block structure is inconsistent.
#[derive(Clone, Debug, thiserror::Error)]
#[error("invalid block structure: {0}")]
pub struct StructureError(pub String);

/// Block pattern (block sizes, kinds, and present blocks) of a [`BlockMatrix`].
#[derive(Clone, Debug)]
pub struct BlockStructure {
    sizes: Vec<usize>,
    kinds: Vec<BlockKind>,
    /// Scalar offset of each block, length `n_blocks + 1`.
    offsets: Vec<usize>,
    /// Block-row pointers into `cols`/`val_off`, length `n_blocks + 1`.
    row_ptr: Vec<usize>,
    /// Sorted block-column indices of each block row (diagonal included).
    cols: Vec<usize>,
    /// Offset into `values` of each block entry (row-major block storage).
    val_off: Vec<usize>,
    /// Each block entry's place in the row-major storage (`val_off`, row stride = its
    /// columns, column stride 1).
    slots: Vec<BlockSlot>,
    nnz_values: usize,
}

/// Where one block of a matrix's values lives: entry (r, c) of the block is
/// `values[offset + r · row_stride + c · col_stride]` (row-major: `(cols, 1)`;
/// column-major: `(1, rows)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlockSlot {
    pub offset: usize,
    pub row_stride: usize,
    pub col_stride: usize,
    /// Number of values of the block.
    pub len: usize,
}

/// One block of a matrix's values with its strides ([`BlockSlot`]), for adding to.
pub struct BlockView<'a> {
    pub values: &'a mut [f64],
    pub row_stride: usize,
    pub col_stride: usize,
}

impl BlockView<'_> {
    /// Index of entry (r, c) in `values`.
    #[inline(always)]
    pub fn at(&self, r: usize, c: usize) -> usize {
        r * self.row_stride + c * self.col_stride
    }

    /// Whether the block is stored row-major (column stride 1).
    #[inline(always)]
    pub fn row_major(&self) -> bool {
        self.col_stride == 1
    }
}

impl BlockStructure {
    /// `sizes[k]` = rows = cols of diagonal block `k`; each coupling `(i, j)`
    /// adds blocks `(i, j)` and `(j, i)`; diagonal blocks are always present;
    /// duplicate couplings are allowed.
    ///
    /// Errors on out-of-range block index, `sizes`/`kinds` length mismatch,
    /// or a zero block size.
    pub fn new(
        sizes: Vec<usize>,
        kinds: Vec<BlockKind>,
        couplings: &[(usize, usize)],
    ) -> Result<Self, StructureError> {
        let n = sizes.len();
        if kinds.len() != n {
            return Err(StructureError(format!(
                "sizes has {} entries but kinds has {}",
                n,
                kinds.len()
            )));
        }
        if let Some(k) = sizes.iter().position(|&s| s == 0) {
            return Err(StructureError(format!("block {k} has zero size")));
        }
        for &(i, j) in couplings {
            if i >= n || j >= n {
                return Err(StructureError(format!(
                    "coupling ({i}, {j}) out of range for {n} blocks"
                )));
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut acc = 0usize;
        offsets.push(0);
        for &s in &sizes {
            acc = acc
                .checked_add(s)
                .ok_or_else(|| StructureError("dimension overflow".into()))?;
            offsets.push(acc);
        }

        // Count per row (with duplicates), then fill, sort, dedup.
        let mut cnt = vec![1usize; n];
        for &(i, j) in couplings {
            if i != j {
                cnt[i] += 1;
                cnt[j] += 1;
            }
        }
        let mut ptr = Vec::with_capacity(n + 1);
        ptr.push(0usize);
        for k in 0..n {
            ptr.push(ptr[k] + cnt[k]);
        }
        let mut raw = vec![0usize; ptr[n]];
        let mut pos: Vec<usize> = ptr[..n].to_vec();
        for k in 0..n {
            raw[pos[k]] = k;
            pos[k] += 1;
        }
        for &(i, j) in couplings {
            if i != j {
                raw[pos[i]] = j;
                pos[i] += 1;
                raw[pos[j]] = i;
                pos[j] += 1;
            }
        }
        let mut row_ptr = Vec::with_capacity(n + 1);
        row_ptr.push(0usize);
        let mut cols = Vec::with_capacity(raw.len());
        for k in 0..n {
            let row = &mut raw[ptr[k]..ptr[k + 1]];
            row.sort_unstable();
            let mut last = usize::MAX;
            for &c in row.iter() {
                if c != last {
                    cols.push(c);
                    last = c;
                }
            }
            row_ptr.push(cols.len());
        }
        let mut val_off = Vec::with_capacity(cols.len());
        let mut slots = Vec::with_capacity(cols.len());
        let mut nnz = 0usize;
        for i in 0..n {
            for &j in &cols[row_ptr[i]..row_ptr[i + 1]] {
                val_off.push(nnz);
                let len = sizes[i]
                    .checked_mul(sizes[j])
                    .ok_or_else(|| StructureError("value count overflow".into()))?;
                slots.push(BlockSlot {
                    offset: nnz,
                    row_stride: sizes[j],
                    col_stride: 1,
                    len,
                });
                nnz = nnz
                    .checked_add(len)
                    .ok_or_else(|| StructureError("value count overflow".into()))?;
            }
        }
        Ok(Self {
            sizes,
            kinds,
            offsets,
            row_ptr,
            cols,
            val_off,
            slots,
            nnz_values: nnz,
        })
    }

    /// Number of diagonal blocks.
    #[inline]
    pub fn n_blocks(&self) -> usize {
        self.sizes.len()
    }

    /// Scalar dimension of the matrix.
    #[inline]
    pub fn dim(&self) -> usize {
        self.offsets[self.sizes.len()]
    }

    /// Size of diagonal block `k`.
    #[inline]
    pub fn block_size(&self, k: usize) -> usize {
        self.sizes[k]
    }

    /// Scalar offset of block `k`.
    #[inline]
    pub fn block_offset(&self, k: usize) -> usize {
        self.offsets[k]
    }

    /// Kind of block `k`.
    #[inline]
    pub fn kind(&self, k: usize) -> BlockKind {
        self.kinds[k]
    }

    /// Offset into [`BlockMatrix::values`] of block `(i, j)` (row-major,
    /// `sizes[i] x sizes[j]`), or `None` if not in the pattern.
    /// `O(log deg(i))`.
    #[inline]
    pub fn entry(&self, i: usize, j: usize) -> Option<usize> {
        self.entry_index(i, j).map(|e| self.val_off[e])
    }

    /// Index of block `(i, j)` among the stored blocks (block rows in order, each by
    /// column), or `None` if not in the pattern: the key of [`BlockMatrix::view`].
    #[inline]
    pub fn entry_index(&self, i: usize, j: usize) -> Option<usize> {
        if i >= self.sizes.len() {
            return None;
        }
        let lo = self.row_ptr[i];
        let hi = self.row_ptr[i + 1];
        self.cols[lo..hi].binary_search(&j).ok().map(|p| lo + p)
    }

    /// Number of stored blocks.
    #[inline]
    pub fn n_entries(&self) -> usize {
        self.cols.len()
    }

    /// Row-major place of each stored block ([`Self::entry_index`] order).
    #[inline]
    pub fn slots(&self) -> &[BlockSlot] {
        &self.slots
    }

    /// Total number of stored scalar values.
    #[inline]
    pub fn nnz_values(&self) -> usize {
        self.nnz_values
    }

    /// Sorted block columns of block row `i` (diagonal included).
    #[inline]
    pub(crate) fn row_cols(&self, i: usize) -> &[usize] {
        &self.cols[self.row_ptr[i]..self.row_ptr[i + 1]]
    }

    /// Value offsets of the blocks of block row `i`, parallel to `row_cols(i)`.
    #[inline]
    pub(crate) fn row_offsets(&self, i: usize) -> &[usize] {
        &self.val_off[self.row_ptr[i]..self.row_ptr[i + 1]]
    }
}

/// Block-sparse matrix: a shared [`BlockStructure`] plus the block values, stored
/// row-major block by block as the structure lays them out — or, as an assembly target
/// only, at the places a factorization gives them ([`Self::with_placement`]).
pub struct BlockMatrix {
    pub structure: Arc<BlockStructure>,
    pub values: Vec<f64>,
    /// The blocks' places when not the structure's row-major layout (the block LU's factor
    /// storage: the matrix is assembled where the factorization works on it).
    placement: Option<Arc<[BlockSlot]>>,
    /// [`Self::fill_zero`] zeroes `values[..zeroed]`: all of them row-major; in the factor
    /// storage the part before the fill blocks, which the factorization assigns itself.
    zeroed: usize,
    /// In the factor storage, [`Self::fill_zero`] zeroes a block when it is first viewed
    /// after it ([`Self::view`]; the assembly's first addition into a block then finds it
    /// in the cache instead of a whole matrix zeroed in one sweep and evicted again, 4 % of
    /// a 10,000-element beam's time): `stamp[e] == epoch` marks block `e` zeroed since.
    /// [`Self::settled_values`] zeroes the blocks not viewed.
    stamp: Vec<u32>,
    epoch: u32,
    lazy: bool,
    /// The values before `zeroed` in no block (zeroed by [`Self::settled_values`]).
    gaps: Vec<std::ops::Range<usize>>,
}

/// A handle for adding into the blocks of a [`BlockMatrix`]: the whole matrix
/// ([`BlockMatrix::target`]) or the blocks one part owns ([`BlockMatrix::part_targets`]),
/// which may be filled on two threads at once. Borrows the matrix mutably.
pub struct BlockTarget<'a> {
    values: *mut f64,
    n_values: usize,
    slots: &'a [BlockSlot],
    stamp: *mut u32,
    epoch: u32,
    lazy: bool,
    /// Owner of each stored block and this handle's part: [`Self::view`] of a block
    /// another part owns panics.
    owner: Option<(&'a [u8], u8)>,
    _matrix: std::marker::PhantomData<&'a mut BlockMatrix>,
}

// SAFETY: the handles of one matrix made together ([`BlockMatrix::part_targets`]) reach
// disjoint blocks (checked in `view`), whose values and stamps do not overlap.
unsafe impl Send for BlockTarget<'_> {}

impl BlockTarget<'_> {
    /// Stored block `e` ([`BlockStructure::entry_index`]) with its strides; zeroed first
    /// when the matrix was lazily cleared ([`BlockMatrix::fill_zero`]).
    #[inline(always)]
    pub fn view(&mut self, e: usize) -> BlockView<'_> {
        if let Some((owner, part)) = self.owner {
            assert_eq!(
                owner[e], part,
                "a part's assembly reached another part's block"
            );
        }
        let s = self.slots[e];
        assert!(s.offset + s.len <= self.n_values);
        // SAFETY: in bounds (above); `&mut self` keeps one view of this handle alive at a
        // time, and the other handles of the same matrix own other blocks.
        let values = unsafe { std::slice::from_raw_parts_mut(self.values.add(s.offset), s.len) };
        if self.lazy {
            // SAFETY: `e` is one of this handle's blocks; the stamps are one per block.
            let st = unsafe { &mut *self.stamp.add(e) };
            if *st != self.epoch {
                *st = self.epoch;
                values.fill(0.0);
            }
        }
        BlockView {
            values,
            row_stride: s.row_stride,
            col_stride: s.col_stride,
        }
    }
}

impl BlockMatrix {
    /// A handle for adding into every block.
    pub fn target(&mut self) -> BlockTarget<'_> {
        self.target_of(None)
    }

    /// Two handles, for the blocks `owner` gives to part 0 and to part 1 (one entry per
    /// stored block; other values belong to neither).
    pub fn part_targets<'a>(&'a mut self, owner: &'a [u8]) -> [BlockTarget<'a>; 2] {
        assert_eq!(
            owner.len(),
            self.structure.n_entries(),
            "one owner per stored block"
        );
        let t = self.target_of(None);
        let a = BlockTarget {
            owner: Some((owner, 0)),
            ..t
        };
        let b = BlockTarget {
            owner: Some((owner, 1)),
            ..t
        };
        [a, b]
    }

    fn target_of<'a>(&'a mut self, owner: Option<(&'a [u8], u8)>) -> BlockTarget<'a> {
        let slots: &[BlockSlot] = match &self.placement {
            Some(p) => p,
            None => &self.structure.slots,
        };
        BlockTarget {
            values: self.values.as_mut_ptr(),
            n_values: self.values.len(),
            slots,
            stamp: self.stamp.as_mut_ptr(),
            epoch: self.epoch,
            lazy: self.lazy,
            owner,
            _matrix: std::marker::PhantomData,
        }
    }
}

impl BlockMatrix {
    /// All-zero matrix with the given structure.
    pub fn zeros(s: Arc<BlockStructure>) -> Self {
        let values = vec![0.0; s.nnz_values()];
        Self {
            structure: s,
            zeroed: values.len(),
            values,
            placement: None,
            stamp: Vec::new(),
            epoch: 0,
            lazy: false,
            gaps: Vec::new(),
        }
    }

    /// All-zero assembly target of `len` values whose blocks live at `placement`
    /// (one per stored block, [`BlockStructure::entry_index`] order) within the first
    /// `zeroed`, the only ones [`Self::fill_zero`] clears. Only [`Self::view`] and
    /// [`Self::fill_zero`] work on it; the matrix-level operations need the row-major
    /// layout.
    pub fn with_placement(
        s: Arc<BlockStructure>,
        placement: Arc<[BlockSlot]>,
        len: usize,
        zeroed: usize,
    ) -> Self {
        assert_eq!(placement.len(), s.n_entries(), "one place per stored block");
        assert!(zeroed <= len);
        assert!(placement.iter().all(|p| p.offset + p.len <= zeroed));
        let mut spans: Vec<(usize, usize)> = placement
            .iter()
            .map(|p| (p.offset, p.offset + p.len))
            .collect();
        spans.sort_unstable();
        let mut gaps = Vec::new();
        let mut at = 0;
        for (a, b) in spans {
            if a > at {
                gaps.push(at..a);
            }
            at = at.max(b);
        }
        if at < zeroed {
            gaps.push(at..zeroed);
        }
        Self {
            structure: s,
            values: vec![0.0; len],
            stamp: vec![0; placement.len()],
            placement: Some(placement),
            zeroed,
            epoch: 0,
            lazy: false,
            gaps,
        }
    }

    /// Whether the blocks are at the structure's row-major places (the matrix-level
    /// operations work).
    #[inline]
    pub fn is_row_major(&self) -> bool {
        self.placement.is_none()
    }

    /// The place of stored block `e` ([`BlockStructure::entry_index`]).
    #[inline(always)]
    pub fn slot(&self, e: usize) -> BlockSlot {
        match &self.placement {
            Some(p) => p[e],
            None => self.structure.slots[e],
        }
    }

    /// Stored block `e` ([`BlockStructure::entry_index`]) with its strides.
    #[inline(always)]
    pub fn view(&mut self, e: usize) -> BlockView<'_> {
        let s = self.slot(e);
        if self.lazy && self.stamp[e] != self.epoch {
            self.stamp[e] = self.epoch;
            self.values[s.offset..s.offset + s.len].fill(0.0);
        }
        BlockView {
            values: &mut self.values[s.offset..s.offset + s.len],
            row_stride: s.row_stride,
            col_stride: s.col_stride,
        }
    }

    fn assert_row_major(&self) {
        assert!(
            self.placement.is_none(),
            "BlockMatrix: a matrix in a factorization's layout is an assembly target only"
        );
    }

    /// Set all stored values to zero (in a factor storage, those of the input blocks).
    /// In a factor storage ([`Self::with_placement`]) each block is zeroed when first
    /// viewed after this call, the others by [`Self::settled_values`].
    pub fn fill_zero(&mut self) {
        if self.placement.is_none() {
            self.values[..self.zeroed].fill(0.0);
            return;
        }
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.fill(0);
            self.epoch = 1;
        }
        self.lazy = true;
    }

    /// The values, after zeroing the blocks no view has touched since [`Self::fill_zero`]
    /// and the values between blocks: what a factorization of the storage reads.
    pub fn settled_values(&mut self) -> &mut Vec<f64> {
        if std::mem::take(&mut self.lazy) {
            let epoch = self.epoch;
            for (e, st) in self.stamp.iter_mut().enumerate() {
                if *st != epoch {
                    *st = epoch;
                    let s = match &self.placement {
                        Some(p) => p[e],
                        None => self.structure.slots[e],
                    };
                    self.values[s.offset..s.offset + s.len].fill(0.0);
                }
            }
            for g in &self.gaps {
                self.values[g.clone()].fill(0.0);
            }
        }
        &mut self.values
    }

    /// Row-major values of block `(i, j)`, if present.
    #[inline]
    pub fn block(&self, i: usize, j: usize) -> Option<&[f64]> {
        self.assert_row_major();
        let s = &*self.structure;
        if j >= s.n_blocks() {
            return None;
        }
        let off = s.entry(i, j)?;
        let len = s.sizes[i] * s.sizes[j];
        Some(&self.values[off..off + len])
    }

    /// Mutable row-major values of block `(i, j)`, if present.
    #[inline]
    pub fn block_mut(&mut self, i: usize, j: usize) -> Option<&mut [f64]> {
        self.assert_row_major();
        let s = &*self.structure;
        if j >= s.n_blocks() {
            return None;
        }
        let off = s.entry(i, j)?;
        let len = s.sizes[i] * s.sizes[j];
        Some(&mut self.values[off..off + len])
    }

    /// Dense `n x n` row-major copy (tests / debugging only).
    pub fn to_dense_rowmajor(&self) -> Vec<f64> {
        self.assert_row_major();
        let s = &*self.structure;
        let n = s.dim();
        let mut d = vec![0.0; n * n];
        for i in 0..s.n_blocks() {
            let (ri, si) = (s.offsets[i], s.sizes[i]);
            for (&j, &off) in s.row_cols(i).iter().zip(s.row_offsets(i)) {
                let (cj, sj) = (s.offsets[j], s.sizes[j]);
                for r in 0..si {
                    let src = &self.values[off + r * sj..off + (r + 1) * sj];
                    d[(ri + r) * n + cj..(ri + r) * n + cj + sj].copy_from_slice(src);
                }
            }
        }
        d
    }

    /// Matrix 1-norm (maximum absolute column sum), computed sparsely.
    pub fn norm_1(&self) -> f64 {
        self.assert_row_major();
        let s = &*self.structure;
        let mut colsum = vec![0.0f64; s.dim()];
        for i in 0..s.n_blocks() {
            let si = s.sizes[i];
            for (&j, &off) in s.row_cols(i).iter().zip(s.row_offsets(i)) {
                let (cj, sj) = (s.offsets[j], s.sizes[j]);
                let cs = &mut colsum[cj..cj + sj];
                for r in 0..si {
                    let row = &self.values[off + r * sj..off + (r + 1) * sj];
                    for (c, v) in cs.iter_mut().zip(row) {
                        *c += v.abs();
                    }
                }
            }
        }
        colsum.into_iter().fold(0.0, f64::max)
    }

    /// `y = A x`.
    pub fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        self.assert_row_major();
        let s = &*self.structure;
        let n = s.dim();
        assert_eq!(x.len(), n, "mul_vec: x has wrong length");
        assert_eq!(y.len(), n, "mul_vec: y has wrong length");
        for i in 0..s.n_blocks() {
            let (ri, si) = (s.offsets[i], s.sizes[i]);
            let yi = &mut y[ri..ri + si];
            yi.fill(0.0);
            for (&j, &off) in s.row_cols(i).iter().zip(s.row_offsets(i)) {
                let (cj, sj) = (s.offsets[j], s.sizes[j]);
                let xj = &x[cj..cj + sj];
                for (r, yr) in yi.iter_mut().enumerate() {
                    let row = &self.values[off + r * sj..off + (r + 1) * sj];
                    let mut acc = 0.0;
                    for (a, b) in row.iter().zip(xj) {
                        acc += a * b;
                    }
                    *yr += acc;
                }
            }
        }
    }

    /// Convert to a faer compressed-sparse-column matrix (all stored block
    /// entries become explicit entries, zeros included; rows sorted).
    pub fn to_faer_csc(&self) -> faer::sparse::SparseColMat<usize, f64> {
        self.assert_row_major();
        let s = &*self.structure;
        let n = s.dim();
        let nnz = s.nnz_values();
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::with_capacity(nnz);
        let mut vals = Vec::with_capacity(nnz);
        col_ptr.push(0usize);
        for j in 0..s.n_blocks() {
            let sj = s.sizes[j];
            // The pattern is structurally symmetric: block column j has the
            // same block indices as block row j (sorted).
            for q in 0..sj {
                for &i in s.row_cols(j) {
                    let off = s.entry(i, j).expect("structurally symmetric pattern");
                    let (ri, si) = (s.offsets[i], s.sizes[i]);
                    for p in 0..si {
                        row_idx.push(ri + p);
                        vals.push(self.values[off + p * sj + q]);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let sym = faer::sparse::SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        faer::sparse::SparseColMat::new(sym, vals)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> BlockMatrix {
        let s = BlockStructure::new(
            vec![2, 1, 3],
            vec![
                BlockKind::Primary,
                BlockKind::Multiplier,
                BlockKind::Primary,
            ],
            &[(0, 1), (1, 2), (1, 0), (0, 1)],
        )
        .unwrap();
        let mut a = BlockMatrix::zeros(Arc::new(s));
        for (k, v) in a.values.iter_mut().enumerate() {
            *v = (k as f64 * 0.37).sin() - 0.2;
        }
        a
    }

    /// In a factor storage `fill_zero` zeroes a block at its first view after it and
    /// `settled_values` the blocks not viewed and the values between blocks; the fill
    /// blocks after `zeroed` are left alone; row-major, it zeroes at once.
    #[test]
    fn factor_storage_is_zeroed_block_by_block() {
        let a = small();
        let s = a.structure.clone();
        let n = s.n_entries();
        // Blocks in reverse order with a gap of 3 values after each, then 5 fill values.
        let mut placement = Vec::new();
        let mut off = 0;
        for e in (0..n).rev() {
            let rm = s.slots()[e];
            placement.push((e, BlockSlot { offset: off, ..rm }));
            off += rm.len + 3;
        }
        placement.sort_by_key(|p| p.0);
        let placement: Arc<[BlockSlot]> = placement.into_iter().map(|p| p.1).collect();
        let (zeroed, len) = (off, off + 5);
        let mut p = BlockMatrix::with_placement(s.clone(), placement.clone(), len, zeroed);
        // The rounds cross the epoch's wrap-around (every stamp reset).
        p.epoch = u32::MAX - 1;
        for round in 0..4 {
            p.values.fill(f64::NAN);
            p.fill_zero();
            // Blocks 0 and 2 written (0 twice), the others not.
            for e in [0, 2, 0] {
                let v = p.view(e);
                for x in v.values.iter_mut() {
                    *x += 1.5;
                }
            }
            let vals = p.settled_values().clone();
            for e in 0..n {
                let sl = placement[e];
                let want = match e {
                    0 => 3.0,
                    2 => 1.5,
                    _ => 0.0,
                };
                assert!(
                    vals[sl.offset..sl.offset + sl.len]
                        .iter()
                        .all(|&x| x == want),
                    "round {round}, block {e}"
                );
            }
            assert!(vals[..zeroed].iter().all(|x| !x.is_nan()), "gaps zeroed");
            assert!(vals[zeroed..].iter().all(|x| x.is_nan()), "fill left alone");
            // Settled: later views do not zero again until the next fill_zero.
            p.view(0).values[0] = 7.0;
            assert_eq!(p.view(0).values[0], 7.0);
        }
        let mut r = small();
        r.fill_zero();
        assert!(r.values.iter().all(|&x| x == 0.0));
    }

    #[test]
    fn structure_basics() {
        let a = small();
        let s = &*a.structure;
        assert_eq!(s.n_blocks(), 3);
        assert_eq!(s.dim(), 6);
        assert_eq!(s.block_offset(2), 3);
        assert_eq!(s.block_size(2), 3);
        assert_eq!(s.kind(1), BlockKind::Multiplier);
        assert!(s.entry(0, 2).is_none());
        assert!(s.entry(2, 0).is_none());
        assert!(s.entry(5, 0).is_none());
        // blocks: (0,0)4 (0,1)2 (1,0)2 (1,1)1 (1,2)3 (2,1)3 (2,2)9
        assert_eq!(s.nnz_values(), 4 + 2 + 2 + 1 + 3 + 3 + 9);
        assert_eq!(s.entry(0, 0), Some(0));
        assert_eq!(s.entry(0, 1), Some(4));
        assert_eq!(s.entry(1, 0), Some(6));
        assert_eq!(a.block(1, 2).unwrap().len(), 3);
        assert!(a.block(0, 7).is_none());
    }

    #[test]
    fn structure_errors() {
        use BlockKind::*;
        assert!(BlockStructure::new(vec![2, 3], vec![Primary], &[]).is_err());
        assert!(BlockStructure::new(vec![2, 0], vec![Primary, Primary], &[]).is_err());
        assert!(BlockStructure::new(vec![2, 3], vec![Primary, Primary], &[(0, 2)]).is_err());
        assert!(BlockStructure::new(vec![2, 3], vec![Primary, Primary], &[(2, 0)]).is_err());
        let e = BlockStructure::new(vec![2, 3], vec![Primary, Primary], &[(0, 5)]).unwrap_err();
        assert!(e.to_string().starts_with("invalid block structure: "));
        assert!(BlockStructure::new(vec![], vec![], &[]).is_ok());
    }

    #[test]
    fn dense_matvec_norm_csc_agree() {
        let a = small();
        let n = a.structure.dim();
        let d = a.to_dense_rowmajor();
        // block (1,2): row 2, cols 3..6
        let b12 = a.block(1, 2).unwrap();
        assert_eq!(&d[2 * n + 3..2 * n + 6], b12);
        assert_eq!(d[3], 0.0);

        let x: Vec<f64> = (0..n).map(|k| 1.0 + k as f64).collect();
        let mut y = vec![0.0; n];
        a.mul_vec(&x, &mut y);
        for r in 0..n {
            let yr: f64 = (0..n).map(|c| d[r * n + c] * x[c]).sum();
            assert!((yr - y[r]).abs() < 1e-13);
        }
        let n1 = (0..n)
            .map(|c| (0..n).map(|r| d[r * n + c].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        assert!((n1 - a.norm_1()).abs() < 1e-13);

        let csc = a.to_faer_csc();
        let dm = csc.to_dense();
        for r in 0..n {
            for c in 0..n {
                assert_eq!(dm[(r, c)], d[r * n + c]);
            }
        }
    }
}
