//! TEMPORARY minimal block structure (replaced by the block-sparse implementation).

use std::collections::HashMap;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockKind {
    Primary,
    Multiplier,
}

#[derive(Clone, Debug, thiserror::Error)]
#[error("invalid block structure: {0}")]
pub struct StructureError(pub String);

#[derive(Clone, Debug)]
pub struct BlockStructure {
    sizes: Vec<usize>,
    kinds: Vec<BlockKind>,
    offsets: Vec<usize>,
    entries: HashMap<(usize, usize), usize>,
    list: Vec<(usize, usize, usize)>,
    nnz: usize,
}

impl BlockStructure {
    pub fn new(
        sizes: Vec<usize>,
        kinds: Vec<BlockKind>,
        couplings: &[(usize, usize)],
    ) -> Result<Self, StructureError> {
        let mut offsets = Vec::with_capacity(sizes.len());
        let mut o = 0;
        for s in &sizes {
            offsets.push(o);
            o += s;
        }
        let mut entries = HashMap::new();
        let mut list = Vec::new();
        let mut nnz = 0;
        let mut add = |i: usize, j: usize, entries: &mut HashMap<(usize, usize), usize>| {
            if let std::collections::hash_map::Entry::Vacant(e) = entries.entry((i, j)) {
                e.insert(nnz);
                list.push((i, j, nnz));
                nnz += sizes[i] * sizes[j];
            }
        };
        for i in 0..sizes.len() {
            add(i, i, &mut entries);
        }
        for &(i, j) in couplings {
            if i >= sizes.len() || j >= sizes.len() {
                return Err(StructureError(format!("coupling ({i}, {j}) out of range")));
            }
            add(i, j, &mut entries);
            add(j, i, &mut entries);
        }
        Ok(Self {
            sizes,
            kinds,
            offsets,
            entries,
            list,
            nnz,
        })
    }
    pub fn n_blocks(&self) -> usize {
        self.sizes.len()
    }
    pub fn dim(&self) -> usize {
        self.sizes.iter().sum()
    }
    pub fn block_size(&self, k: usize) -> usize {
        self.sizes[k]
    }
    pub fn block_offset(&self, k: usize) -> usize {
        self.offsets[k]
    }
    pub fn kind(&self, k: usize) -> BlockKind {
        self.kinds[k]
    }
    pub fn entry(&self, i: usize, j: usize) -> Option<usize> {
        self.entries.get(&(i, j)).copied()
    }
    pub fn nnz_values(&self) -> usize {
        self.nnz
    }
}

pub struct BlockMatrix {
    pub structure: Arc<BlockStructure>,
    pub values: Vec<f64>,
}

impl BlockMatrix {
    pub fn zeros(s: Arc<BlockStructure>) -> Self {
        let n = s.nnz_values();
        Self {
            structure: s,
            values: vec![0.0; n],
        }
    }
    pub fn fill_zero(&mut self) {
        self.values.fill(0.0);
    }
    pub fn block(&self, i: usize, j: usize) -> Option<&[f64]> {
        let o = self.structure.entry(i, j)?;
        Some(&self.values[o..o + self.structure.sizes[i] * self.structure.sizes[j]])
    }
    pub fn to_dense_rowmajor(&self) -> Vec<f64> {
        let s = &self.structure;
        let n = s.dim();
        let mut d = vec![0.0; n * n];
        for &(i, j, o) in &s.list {
            let (ri, cj) = (s.sizes[i], s.sizes[j]);
            for a in 0..ri {
                for b in 0..cj {
                    d[(s.offsets[i] + a) * n + s.offsets[j] + b] += self.values[o + a * cj + b];
                }
            }
        }
        d
    }
    pub fn norm_1(&self) -> f64 {
        let n = self.structure.dim();
        let d = self.to_dense_rowmajor();
        (0..n)
            .map(|j| (0..n).map(|i| d[i * n + j].abs()).sum::<f64>())
            .fold(0.0, f64::max)
    }
    pub fn to_faer_csc(&self) -> faer::sparse::SparseColMat<usize, f64> {
        let s = &self.structure;
        let mut t = Vec::new();
        for &(i, j, o) in &s.list {
            let (ri, cj) = (s.sizes[i], s.sizes[j]);
            for a in 0..ri {
                for b in 0..cj {
                    t.push(faer::sparse::Triplet::new(
                        s.offsets[i] + a,
                        s.offsets[j] + b,
                        self.values[o + a * cj + b],
                    ));
                }
            }
        }
        faer::sparse::SparseColMat::try_new_from_triplets(s.dim(), s.dim(), &t)
            .expect("valid triplets")
    }
}
