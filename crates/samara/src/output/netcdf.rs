//! Minimal, dependency-free (std + `thiserror`) incremental NetCDF-3 writer.
//!
//! Produces NetCDF classic files in the **64-bit offset** variant ("CDF-2",
//! magic `C D F \x02`) as described in the *NetCDF Classic Format
//! Specification*: big-endian, 4-byte aligned header and data, `begin`
//! offsets stored as 64-bit integers.
//!
//! # Model
//!
//! * [`Definition`] collects dimensions, variables and attributes (define mode).
//!   At most one dimension may be the UNLIMITED record dimension; a variable is
//!   a record variable iff its first dimension is the record dimension.
//! * [`Definition::create`] lays the file out, writes the header, an optional
//!   block of reserved (zero) bytes after the header, and all fixed-size
//!   variables pre-filled with their fill value. It refuses to overwrite an
//!   existing file (`O_CREAT|O_EXCL`).
//! * [`Writer`] writes fixed variables (`put_fixed_*`) and appends records:
//!   stage values with [`Writer::set_record_f64`] / [`Writer::set_record_i32`],
//!   then [`Writer::commit_record`]. A commit performs one positioned write of
//!   the whole record (all record variables, interleaved as the format
//!   requires) followed by one 4-byte positioned write of `numrecs` in the
//!   header. No allocation happens per record (a preallocated record buffer is
//!   reset from a preallocated fill template).
//!
//! # Crash consistency
//!
//! Record data is written *before* `numrecs` is bumped, so if the process dies
//! at any point the file on disk is a valid NetCDF file containing every record
//! whose `commit_record` returned (a partially written trailing record is
//! beyond `numrecs` and ignored by readers). Writes go straight to the OS with
//! `pwrite` (no user-space buffering), so this holds for process crashes
//! without any flushing. For durability against power loss call
//! [`Writer::sync`] (fsync) at the cadence you need; [`Writer::finish`] syncs.
//!
//! # Fill values
//!
//! Values never written (fixed variables not `put`, record variables not `set`
//! for a committed record) hold the variable's fill value: the `_FillValue`
//! attribute if one was given (must be `AttrValue::Double` for `Double`
//! variables / `AttrValue::Int` for `Int` variables, only the first element is
//! used), otherwise the NetCDF default fill (`NC_FILL_DOUBLE` =
//! `NC_FILL_FLOAT` = 9.9692099683868690e36, `NC_FILL_INT` = -2147483647,
//! `NC_FILL_SHORT` = -32767, `NC_FILL_BYTE` = -127, `NC_FILL_CHAR` = 0).
//! netCDF4-python masks the default fills automatically; xarray only masks
//! values equal to an explicit `_FillValue`/`missing_value` attribute, so set
//! `_FillValue` (e.g. NaN) if you want xarray to see NaN.
//!
//! # Reserved header space
//!
//! [`Definition::reserve_header`] leaves zero bytes between the end of the
//! header and the first variable's `begin` (permitted by the spec; readers
//! locate data via `begin`). [`Writer::set_global_attr`] re-serialises the
//! header in place; it succeeds as long as the new header still ends at or
//! before the first `begin`, otherwise it returns [`NcError::HeaderFull`] and
//! leaves the file unchanged. Data offsets never move.
//!
//! # Limits
//!
//! Names are written as given (callers should use ASCII / NFC names); basic
//! validity (non-empty, no `/`, no control chars, no leading punctuation other
//! than `_`, no trailing space) and uniqueness are checked. Per CDF-2 rules a
//! variable whose size exceeds 4 GiB - 4 bytes is only allowed as the last
//! fixed variable (when there are no record variables) or the last record
//! variable. `numrecs` is limited to `i32::MAX`.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------------------
// Public types
// ---------------------------------------------------------------------------

/// External NetCDF-3 data types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NcType {
    Byte,
    Char,
    Short,
    Int,
    Float,
    Double,
}

impl NcType {
    fn code(self) -> u32 {
        match self {
            NcType::Byte => 1,
            NcType::Char => 2,
            NcType::Short => 3,
            NcType::Int => 4,
            NcType::Float => 5,
            NcType::Double => 6,
        }
    }

    /// Size of one element in bytes.
    pub fn size(self) -> usize {
        match self {
            NcType::Byte | NcType::Char => 1,
            NcType::Short => 2,
            NcType::Int | NcType::Float => 4,
            NcType::Double => 8,
        }
    }

    /// Big-endian bytes of the NetCDF default fill value (first `size()` bytes valid).
    fn default_fill(self) -> [u8; 8] {
        let mut b = [0u8; 8];
        match self {
            NcType::Byte => b[0] = (-127i8) as u8,
            NcType::Char => b[0] = 0,
            NcType::Short => b[..2].copy_from_slice(&(-32767i16).to_be_bytes()),
            NcType::Int => b[..4].copy_from_slice(&(-2147483647i32).to_be_bytes()),
            NcType::Float => b[..4].copy_from_slice(&NC_FILL_FLOAT.to_be_bytes()),
            NcType::Double => b.copy_from_slice(&NC_FILL_DOUBLE.to_be_bytes()),
        }
        b
    }
}

/// NetCDF default fill value for `double` variables.
pub const NC_FILL_DOUBLE: f64 = 9.969_209_968_386_869e36;
/// NetCDF default fill value for `float` variables.
pub const NC_FILL_FLOAT: f32 = 9.969_21e36;
/// NetCDF default fill value for `int` variables.
pub const NC_FILL_INT: i32 = -2_147_483_647;

/// Attribute values (written as NC_CHAR, NC_DOUBLE and NC_INT respectively).
#[derive(Debug, Clone, PartialEq)]
pub enum AttrValue {
    Text(String),
    Double(Vec<f64>),
    Int(Vec<i32>),
}

impl AttrValue {
    fn nc_type(&self) -> NcType {
        match self {
            AttrValue::Text(_) => NcType::Char,
            AttrValue::Double(_) => NcType::Double,
            AttrValue::Int(_) => NcType::Int,
        }
    }
}

impl From<&str> for AttrValue {
    fn from(s: &str) -> Self {
        AttrValue::Text(s.to_owned())
    }
}

/// Handle of a dimension inside one [`Definition`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DimId(usize);

/// Handle of a variable inside one [`Definition`] / its [`Writer`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct VarId(usize);

/// Errors of the writer.
#[derive(Debug, thiserror::Error)]
pub enum NcError {
    #[error("I/O error on '{}': {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("refusing to overwrite existing file '{}'", .0.display())]
    Exists(PathBuf),
    #[error("invalid NetCDF definition: {0}")]
    Definition(String),
    #[error(
        "NetCDF header full: rewritten header needs {needed} bytes but only {available} are \
         available before the first variable (increase Definition::reserve_header)"
    )]
    HeaderFull { needed: usize, available: usize },
    #[error("variable '{var}': expected {expected} values, got {got}")]
    WrongShape {
        var: String,
        expected: usize,
        got: usize,
    },
    #[error("variable '{var}' of type {ty:?} cannot be written with {op}")]
    TypeMismatch {
        var: String,
        ty: NcType,
        op: &'static str,
    },
    #[error("variable '{var}': value {value} is not representable as {ty:?}")]
    Range { var: String, value: f64, ty: NcType },
    #[error("variable '{0}' is a record variable; use set_record_* + commit_record")]
    NotFixed(String),
    #[error("variable '{0}' is not a record variable; use put_fixed_*")]
    NotRecord(String),
    #[error("variable '{var}': string #{index} is {len} bytes, longer than the {max} available")]
    StringTooLong {
        var: String,
        index: usize,
        len: usize,
        max: usize,
    },
    #[error("global attribute '{name}' has type {existing:?}, cannot rewrite it as {new:?}")]
    AttrTypeMismatch {
        name: String,
        existing: NcType,
        new: NcType,
    },
    #[error("invalid variable id {0:?} (from another Definition?)")]
    BadVarId(VarId),
    #[error("the file has no unlimited (record) dimension")]
    NoRecordDim,
    #[error("too many records for NetCDF-3 (max {max})")]
    TooManyRecords { max: u64 },
}

// ---------------------------------------------------------------------------
// Schema (shared by define and data mode)
// ---------------------------------------------------------------------------

#[derive(Debug, Clone)]
struct DimDef {
    name: String,
    /// `None` = UNLIMITED.
    len: Option<usize>,
}

#[derive(Debug, Clone)]
struct VarDef {
    name: String,
    ty: NcType,
    dims: Vec<usize>,
    attrs: Vec<(String, AttrValue)>,
}

#[derive(Debug, Clone, Default)]
struct Schema {
    dims: Vec<DimDef>,
    vars: Vec<VarDef>,
    gattrs: Vec<(String, AttrValue)>,
}

/// Per-variable layout computed at `create`.
#[derive(Debug, Clone)]
struct VarLayout {
    is_record: bool,
    /// Elements of the whole variable (fixed) or of one record slab (record var).
    nelems: usize,
    /// Unpadded byte size (nelems * type size).
    nbytes: usize,
    /// `vsize` field written in the header.
    vsize_hdr: u32,
    /// Absolute file offset of the data (first record for record vars).
    begin: u64,
    /// Offset of this variable's slab inside one record (record vars only).
    rec_off: usize,
    /// Big-endian fill bytes (first `ty.size()` valid).
    fill: [u8; 8],
}

const NC_DIMENSION: u32 = 0x0A;
const NC_VARIABLE: u32 = 0x0B;
const NC_ATTRIBUTE: u32 = 0x0C;
/// Largest `vsize` representable in CDF-2 (larger vars store 2^32-1).
const MAX_VSIZE: u64 = (u32::MAX as u64) - 3;
const MAX_NUMRECS: u64 = i32::MAX as u64;

fn pad4(n: usize) -> usize {
    (n + 3) & !3
}

fn put_u32(out: &mut Vec<u8>, v: u32) {
    out.extend_from_slice(&v.to_be_bytes());
}

fn put_name(out: &mut Vec<u8>, name: &str) {
    put_u32(out, name.len() as u32);
    out.extend_from_slice(name.as_bytes());
    out.resize(pad4(out.len()), 0);
}

fn put_attr_list(out: &mut Vec<u8>, attrs: &[(String, AttrValue)]) {
    if attrs.is_empty() {
        put_u32(out, 0); // ABSENT = ZERO ZERO
        put_u32(out, 0);
        return;
    }
    put_u32(out, NC_ATTRIBUTE);
    put_u32(out, attrs.len() as u32);
    for (name, v) in attrs {
        put_name(out, name);
        put_u32(out, v.nc_type().code());
        match v {
            AttrValue::Text(s) => {
                put_u32(out, s.len() as u32);
                out.extend_from_slice(s.as_bytes());
            }
            AttrValue::Double(xs) => {
                put_u32(out, xs.len() as u32);
                for x in xs {
                    out.extend_from_slice(&x.to_be_bytes());
                }
            }
            AttrValue::Int(xs) => {
                put_u32(out, xs.len() as u32);
                for x in xs {
                    out.extend_from_slice(&x.to_be_bytes());
                }
            }
        }
        out.resize(pad4(out.len()), 0);
    }
}

impl Schema {
    fn record_dim(&self) -> Option<usize> {
        self.dims.iter().position(|d| d.len.is_none())
    }

    fn is_record_var(&self, v: &VarDef) -> bool {
        v.dims.first().is_some_and(|&d| self.dims[d].len.is_none())
    }

    /// Serialise the header. `layout` may be empty (sizing pass: zeros written).
    fn encode_header(&self, numrecs: u32, layout: &[VarLayout], out: &mut Vec<u8>) {
        out.clear();
        out.extend_from_slice(b"CDF\x02");
        put_u32(out, numrecs);
        if self.dims.is_empty() {
            put_u32(out, 0);
            put_u32(out, 0);
        } else {
            put_u32(out, NC_DIMENSION);
            put_u32(out, self.dims.len() as u32);
            for d in &self.dims {
                put_name(out, &d.name);
                put_u32(out, d.len.unwrap_or(0) as u32);
            }
        }
        put_attr_list(out, &self.gattrs);
        if self.vars.is_empty() {
            put_u32(out, 0);
            put_u32(out, 0);
        } else {
            put_u32(out, NC_VARIABLE);
            put_u32(out, self.vars.len() as u32);
            for (i, v) in self.vars.iter().enumerate() {
                put_name(out, &v.name);
                put_u32(out, v.dims.len() as u32);
                for &d in &v.dims {
                    put_u32(out, d as u32);
                }
                put_attr_list(out, &v.attrs);
                put_u32(out, v.ty.code());
                let (vsize, begin) = layout.get(i).map_or((0, 0), |l| (l.vsize_hdr, l.begin));
                put_u32(out, vsize);
                out.extend_from_slice(&begin.to_be_bytes());
            }
        }
    }
}

fn validate_name(name: &str) -> Result<(), String> {
    let bad = name.is_empty()
        || name.contains('/')
        || name.chars().any(|c| c.is_control())
        || name.ends_with(' ')
        || name.starts_with(|c: char| c.is_ascii_punctuation() && c != '_')
        || name.len() > 256;
    if bad {
        Err(format!("invalid NetCDF name {name:?}"))
    } else {
        Ok(())
    }
}

fn set_attr(list: &mut Vec<(String, AttrValue)>, name: &str, v: AttrValue) {
    match list.iter_mut().find(|(n, _)| n == name) {
        Some(slot) => slot.1 = v,
        None => list.push((name.to_owned(), v)),
    }
}

// ---------------------------------------------------------------------------
// Define mode
// ---------------------------------------------------------------------------

/// Define mode: collect dimensions, variables and attributes, then [`create`](Self::create).
///
/// Definition mistakes (bad names, duplicates, misplaced record dimension, ...)
/// are collected and reported by `create` as [`NcError::Definition`].
#[derive(Debug, Clone, Default)]
pub struct Definition {
    schema: Schema,
    reserve: usize,
    errors: Vec<String>,
}

impl Definition {
    pub fn new() -> Self {
        Self::default()
    }

    fn check_name(&mut self, name: &str, taken: bool, what: &str) {
        if let Err(e) = validate_name(name) {
            self.errors.push(format!("{what}: {e}"));
        }
        if taken {
            self.errors.push(format!("{what} '{name}' defined twice"));
        }
    }

    /// Add a fixed-length dimension.
    pub fn add_dim(&mut self, name: &str, len: usize) -> DimId {
        let taken = self.schema.dims.iter().any(|d| d.name == name);
        self.check_name(name, taken, "dimension");
        if len == 0 || len > i32::MAX as usize {
            self.errors.push(format!(
                "dimension '{name}': length {len} must be in 1..=i32::MAX"
            ));
        }
        self.schema.dims.push(DimDef {
            name: name.to_owned(),
            len: Some(len),
        });
        DimId(self.schema.dims.len() - 1)
    }

    /// The fixed dimension `name` of length `len`: the existing one if it is defined
    /// already (a different length is an error), a new one otherwise.
    pub fn dim(&mut self, name: &str, len: usize) -> DimId {
        match self.schema.dims.iter().position(|d| d.name == name) {
            Some(i) => {
                if self.schema.dims[i].len != Some(len) {
                    self.errors.push(format!(
                        "dimension '{name}' of length {len} is defined already with another length"
                    ));
                }
                DimId(i)
            }
            None => self.add_dim(name, len),
        }
    }

    /// Add the UNLIMITED (record) dimension; at most one per file.
    pub fn add_record_dim(&mut self, name: &str) -> DimId {
        let taken = self.schema.dims.iter().any(|d| d.name == name);
        self.check_name(name, taken, "dimension");
        if self.schema.record_dim().is_some() {
            self.errors.push(format!(
                "dimension '{name}': only one unlimited dimension is allowed"
            ));
        }
        self.schema.dims.push(DimDef {
            name: name.to_owned(),
            len: None,
        });
        DimId(self.schema.dims.len() - 1)
    }

    /// Add a variable. It is a record variable iff `dims[0]` is the record dimension.
    pub fn add_var(&mut self, name: &str, ty: NcType, dims: &[DimId]) -> VarId {
        let taken = self.schema.vars.iter().any(|v| v.name == name);
        self.check_name(name, taken, "variable");
        for (k, d) in dims.iter().enumerate() {
            match self.schema.dims.get(d.0) {
                None => self
                    .errors
                    .push(format!("variable '{name}': unknown dimension id {}", d.0)),
                Some(dd) if dd.len.is_none() && k != 0 => self.errors.push(format!(
                    "variable '{name}': the unlimited dimension must be the first dimension"
                )),
                _ => {}
            }
        }
        self.schema.vars.push(VarDef {
            name: name.to_owned(),
            ty,
            dims: dims.iter().map(|d| d.0).collect(),
            attrs: Vec::new(),
        });
        VarId(self.schema.vars.len() - 1)
    }

    /// Add (or replace) a variable attribute.
    pub fn add_var_attr(&mut self, var: VarId, name: &str, v: AttrValue) {
        if let Err(e) = validate_name(name) {
            self.errors.push(format!("attribute: {e}"));
        }
        match self.schema.vars.get_mut(var.0) {
            Some(vd) => set_attr(&mut vd.attrs, name, v),
            None => self
                .errors
                .push(format!("attribute '{name}': unknown variable id {}", var.0)),
        }
    }

    /// Add (or replace) a global attribute.
    pub fn add_global_attr(&mut self, name: &str, v: AttrValue) {
        if let Err(e) = validate_name(name) {
            self.errors.push(format!("global attribute: {e}"));
        }
        set_attr(&mut self.schema.gattrs, name, v);
    }

    /// Bytes of spare header space to reserve so that global attributes can be
    /// rewritten later with longer values (see [`Writer::set_global_attr`]).
    pub fn reserve_header(&mut self, bytes: usize) {
        self.reserve = bytes;
    }

    fn compute_layout(
        &self,
        header_len: usize,
    ) -> Result<(Vec<VarLayout>, u64, u64, usize), NcError> {
        let s = &self.schema;
        let data_start = pad4(header_len + self.reserve) as u64;
        let mut layout = Vec::with_capacity(s.vars.len());
        let n_fixed = s.vars.iter().filter(|v| !s.is_record_var(v)).count();
        let n_rec = s.vars.len() - n_fixed;
        let (mut fixed_seen, mut rec_seen) = (0usize, 0usize);
        for v in &s.vars {
            let is_record = s.is_record_var(v);
            let skip = usize::from(is_record);
            let mut nelems: usize = 1;
            for &d in &v.dims[skip..] {
                nelems = nelems
                    .checked_mul(s.dims[d].len.unwrap_or(1))
                    .ok_or_else(|| {
                        NcError::Definition(format!("variable '{}' too large", v.name))
                    })?;
            }
            let nbytes = nelems
                .checked_mul(v.ty.size())
                .ok_or_else(|| NcError::Definition(format!("variable '{}' too large", v.name)))?;
            let padded = pad4(nbytes) as u64;
            let last = if is_record {
                rec_seen += 1;
                rec_seen == n_rec
            } else {
                fixed_seen += 1;
                fixed_seen == n_fixed && n_rec == 0
            };
            let vsize_hdr = if padded <= MAX_VSIZE {
                padded as u32
            } else if last {
                u32::MAX
            } else {
                return Err(NcError::Definition(format!(
                    "variable '{}' is larger than 4 GiB; CDF-2 only allows this for the last variable",
                    v.name
                )));
            };
            let fill = fill_for(v)?;
            layout.push(VarLayout {
                is_record,
                nelems,
                nbytes,
                vsize_hdr,
                begin: 0,
                rec_off: 0,
                fill,
            });
        }
        // Fixed variables first (in definition order), then the record section.
        let mut off = data_start;
        for l in layout.iter_mut().filter(|l| !l.is_record) {
            l.begin = off;
            off += pad4(l.nbytes) as u64;
        }
        let rec_begin = off;
        let mut recsize = 0usize;
        for l in layout.iter_mut().filter(|l| l.is_record) {
            l.begin = rec_begin + recsize as u64;
            l.rec_off = recsize;
            recsize += pad4(l.nbytes);
        }
        // Special case of the spec: a single record variable is not padded
        // between records (matters only for byte/char/short).
        if n_rec == 1 {
            recsize = layout.iter().find(|l| l.is_record).map_or(0, |l| l.nbytes);
        }
        Ok((layout, data_start, rec_begin, recsize))
    }

    /// Create the file (fails with [`NcError::Exists`] if it already exists),
    /// write header + reserved space + fill-valued fixed variables and switch
    /// to data mode.
    pub fn create(self, path: &Path) -> Result<Writer, NcError> {
        if !self.errors.is_empty() {
            return Err(NcError::Definition(self.errors.join("; ")));
        }
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|e| {
                if e.kind() == io::ErrorKind::AlreadyExists {
                    NcError::Exists(path.to_owned())
                } else {
                    NcError::Io {
                        path: path.to_owned(),
                        source: e,
                    }
                }
            })?;
        self.start(Target::File(file), path)
    }

    /// [`Self::create`] into memory: the same bytes, kept in the [`Writer`] and handed
    /// back by [`Writer::into_bytes`]; `name` only labels errors.
    pub fn create_in_memory(self, name: &Path) -> Result<Writer, NcError> {
        if !self.errors.is_empty() {
            return Err(NcError::Definition(self.errors.join("; ")));
        }
        self.start(Target::Memory(Vec::new()), name)
    }

    fn start(self, mut target: Target, path: &Path) -> Result<Writer, NcError> {
        let io_err = |source: io::Error| NcError::Io {
            path: path.to_owned(),
            source,
        };
        let mut header = Vec::new();
        self.schema.encode_header(0, &[], &mut header);
        let (layout, data_start, rec_begin, recsize) = self.compute_layout(header.len())?;
        self.schema.encode_header(0, &layout, &mut header);

        // Header, reserved zeros, then fixed variables pre-filled.
        {
            let mut w = BufWriter::with_capacity(1 << 16, target.sink());
            w.write_all(&header).map_err(io_err)?;
            let zeros = [0u8; 4096];
            let mut left = data_start as usize - header.len();
            while left > 0 {
                let n = left.min(zeros.len());
                w.write_all(&zeros[..n]).map_err(io_err)?;
                left -= n;
            }
            for (v, l) in self.schema.vars.iter().zip(&layout) {
                if l.is_record {
                    continue;
                }
                let sz = v.ty.size();
                for _ in 0..l.nelems {
                    w.write_all(&l.fill[..sz]).map_err(io_err)?;
                }
                w.write_all(&zeros[..pad4(l.nbytes) - l.nbytes])
                    .map_err(io_err)?;
            }
            w.flush().map_err(io_err)?;
        }

        let mut rec_template = vec![0u8; recsize];
        for (v, l) in self.schema.vars.iter().zip(&layout) {
            if l.is_record {
                let sz = v.ty.size();
                for chunk in rec_template[l.rec_off..l.rec_off + l.nbytes].chunks_exact_mut(sz) {
                    chunk.copy_from_slice(&l.fill[..sz]);
                }
            }
        }
        Ok(Writer {
            file: target,
            path: path.to_owned(),
            has_record_dim: self.schema.record_dim().is_some(),
            schema: self.schema,
            layout,
            data_start,
            header_len: header.len(),
            header_buf: header,
            rec_begin,
            recsize,
            numrecs: 0,
            rec_buf: rec_template.clone(),
            rec_template,
            scratch: Vec::new(),
        })
    }
}

fn fill_for(v: &VarDef) -> Result<[u8; 8], NcError> {
    let mut fill = v.ty.default_fill();
    if let Some((_, a)) = v.attrs.iter().find(|(n, _)| n == "_FillValue") {
        match (a, v.ty) {
            (AttrValue::Double(x), NcType::Double) if x.len() == 1 => {
                fill = x[0].to_be_bytes();
            }
            (AttrValue::Int(x), NcType::Int) if x.len() == 1 => {
                fill[..4].copy_from_slice(&x[0].to_be_bytes());
            }
            _ => {
                return Err(NcError::Definition(format!(
                    "variable '{}': _FillValue must be a single value of the variable's type \
                     (Double for double, Int for int variables)",
                    v.name
                )));
            }
        }
    }
    Ok(fill)
}

// ---------------------------------------------------------------------------
// Value encoding
// ---------------------------------------------------------------------------

fn encode_f64(out: &mut [u8], ty: NcType, data: &[f64], var: &str) -> Result<(), NcError> {
    let range = |value: f64| NcError::Range {
        var: var.to_owned(),
        value,
        ty,
    };
    match ty {
        NcType::Double => {
            for (c, &x) in out.chunks_exact_mut(8).zip(data) {
                c.copy_from_slice(&x.to_be_bytes());
            }
        }
        NcType::Float => {
            for (c, &x) in out.chunks_exact_mut(4).zip(data) {
                if x.is_finite() && x.abs() > f32::MAX as f64 {
                    return Err(range(x));
                }
                c.copy_from_slice(&(x as f32).to_be_bytes());
            }
        }
        NcType::Int => {
            for (c, &x) in out.chunks_exact_mut(4).zip(data) {
                if !(x >= i32::MIN as f64 && x <= i32::MAX as f64) {
                    return Err(range(x));
                }
                c.copy_from_slice(&(x as i32).to_be_bytes());
            }
        }
        NcType::Short => {
            for (c, &x) in out.chunks_exact_mut(2).zip(data) {
                if !(x >= i16::MIN as f64 && x <= i16::MAX as f64) {
                    return Err(range(x));
                }
                c.copy_from_slice(&(x as i16).to_be_bytes());
            }
        }
        NcType::Byte => {
            for (c, &x) in out.iter_mut().zip(data) {
                if !(x >= i8::MIN as f64 && x <= i8::MAX as f64) {
                    return Err(range(x));
                }
                *c = x as i8 as u8;
            }
        }
        NcType::Char => {
            return Err(NcError::TypeMismatch {
                var: var.to_owned(),
                ty,
                op: "f64 values",
            });
        }
    }
    Ok(())
}

fn encode_i32(out: &mut [u8], ty: NcType, data: &[i32], var: &str) -> Result<(), NcError> {
    let range = |value: i32| NcError::Range {
        var: var.to_owned(),
        value: value as f64,
        ty,
    };
    match ty {
        NcType::Double => {
            for (c, &x) in out.chunks_exact_mut(8).zip(data) {
                c.copy_from_slice(&(x as f64).to_be_bytes());
            }
        }
        NcType::Float => {
            for (c, &x) in out.chunks_exact_mut(4).zip(data) {
                c.copy_from_slice(&(x as f32).to_be_bytes());
            }
        }
        NcType::Int => {
            for (c, &x) in out.chunks_exact_mut(4).zip(data) {
                c.copy_from_slice(&x.to_be_bytes());
            }
        }
        NcType::Short => {
            for (c, &x) in out.chunks_exact_mut(2).zip(data) {
                let y = i16::try_from(x).map_err(|_| range(x))?;
                c.copy_from_slice(&y.to_be_bytes());
            }
        }
        NcType::Byte => {
            for (c, &x) in out.iter_mut().zip(data) {
                *c = i8::try_from(x).map_err(|_| range(x))? as u8;
            }
        }
        NcType::Char => {
            return Err(NcError::TypeMismatch {
                var: var.to_owned(),
                ty,
                op: "i32 values",
            });
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Data mode
// ---------------------------------------------------------------------------

/// Where a [`Writer`]'s bytes go: a file (positioned writes straight to the OS) or a
/// buffer in memory holding the same bytes.
#[derive(Debug)]
enum Target {
    File(File),
    Memory(Vec<u8>),
}

impl Target {
    fn write_all_at(&mut self, buf: &[u8], offset: u64) -> io::Result<()> {
        match self {
            Target::File(f) => f.write_all_at(buf, offset),
            Target::Memory(m) => {
                let start = usize::try_from(offset)
                    .map_err(|_| io::Error::other("offset beyond the address space"))?;
                let end = start
                    .checked_add(buf.len())
                    .ok_or_else(|| io::Error::other("offset beyond the address space"))?;
                if m.len() < end {
                    m.resize(end, 0);
                }
                m[start..end].copy_from_slice(buf);
                Ok(())
            }
        }
    }

    /// A sequential writer from the start (used once, to lay the file out).
    fn sink(&mut self) -> Sink<'_> {
        Sink {
            target: self,
            pos: 0,
        }
    }
}

struct Sink<'a> {
    target: &'a mut Target,
    pos: u64,
}

impl Write for Sink<'_> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.target.write_all_at(buf, self.pos)?;
        self.pos += buf.len() as u64;
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

/// Data mode: write fixed variables, append records, rewrite global attributes.
///
/// Dropping a `Writer` without [`finish`](Self::finish) leaves a valid file
/// with all committed records (staged, uncommitted values are discarded).
#[derive(Debug)]
pub struct Writer {
    file: Target,
    path: PathBuf,
    schema: Schema,
    layout: Vec<VarLayout>,
    has_record_dim: bool,
    /// Start of the data section = first variable's `begin`; header must fit below it.
    data_start: u64,
    /// Length of the header currently on disk.
    header_len: usize,
    header_buf: Vec<u8>,
    rec_begin: u64,
    recsize: usize,
    numrecs: u64,
    rec_buf: Vec<u8>,
    rec_template: Vec<u8>,
    scratch: Vec<u8>,
}

impl Writer {
    fn io_err(&self, source: io::Error) -> NcError {
        NcError::Io {
            path: self.path.clone(),
            source,
        }
    }

    fn var(&self, var: VarId) -> Result<(&VarDef, &VarLayout), NcError> {
        match (self.schema.vars.get(var.0), self.layout.get(var.0)) {
            (Some(v), Some(l)) => Ok((v, l)),
            _ => Err(NcError::BadVarId(var)),
        }
    }

    fn fixed(&self, var: VarId, got: usize) -> Result<(&VarDef, &VarLayout), NcError> {
        let (v, l) = self.var(var)?;
        if l.is_record {
            return Err(NcError::NotFixed(v.name.clone()));
        }
        if got != l.nelems {
            return Err(NcError::WrongShape {
                var: v.name.clone(),
                expected: l.nelems,
                got,
            });
        }
        Ok((v, l))
    }

    fn write_scratch_at(&mut self, begin: u64) -> Result<(), NcError> {
        self.file
            .write_all_at(&self.scratch, begin)
            .map_err(|e| self.io_err(e))
    }

    /// Path of the file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of committed records.
    pub fn num_records(&self) -> u64 {
        self.numrecs
    }

    /// Whether the bytes go to memory ([`Definition::create_in_memory`]), not to a file.
    pub fn is_in_memory(&self) -> bool {
        matches!(self.file, Target::Memory(_))
    }

    /// Bytes of the file once it holds `records` records: header, fixed variables, then
    /// `records` × the record size (saturating).
    pub fn size_with_records(&self, records: u64) -> u64 {
        (self.recsize as u64)
            .saturating_mul(records)
            .saturating_add(self.rec_begin)
    }

    /// Write a whole non-record variable from f64 values (converted to its type;
    /// integer types are range-checked and truncated).
    pub fn put_fixed_f64(&mut self, var: VarId, data: &[f64]) -> Result<(), NcError> {
        let (v, l) = self.fixed(var, data.len())?;
        let (ty, nbytes, begin) = (v.ty, l.nbytes, l.begin);
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        scratch.resize(nbytes, 0);
        let r = encode_f64(&mut scratch, ty, data, &self.schema.vars[var.0].name);
        self.scratch = scratch;
        r?;
        self.write_scratch_at(begin)
    }

    /// Write a whole non-record variable from i32 values (converted to its type).
    pub fn put_fixed_i32(&mut self, var: VarId, data: &[i32]) -> Result<(), NcError> {
        let (v, l) = self.fixed(var, data.len())?;
        let (ty, nbytes, begin) = (v.ty, l.nbytes, l.begin);
        let mut scratch = std::mem::take(&mut self.scratch);
        scratch.clear();
        scratch.resize(nbytes, 0);
        let r = encode_i32(&mut scratch, ty, data, &self.schema.vars[var.0].name);
        self.scratch = scratch;
        r?;
        self.write_scratch_at(begin)
    }

    /// Write a whole non-record `Char` variable of shape `(..., strlen)`: one
    /// string per product of the leading dimensions, each padded with `\0`
    /// (an error if longer than `strlen` bytes).
    pub fn put_fixed_text(&mut self, var: VarId, strings: &[&str]) -> Result<(), NcError> {
        let (v, l) = self.var(var)?;
        if l.is_record {
            return Err(NcError::NotFixed(v.name.clone()));
        }
        if v.ty != NcType::Char {
            return Err(NcError::TypeMismatch {
                var: v.name.clone(),
                ty: v.ty,
                op: "put_fixed_text",
            });
        }
        let strlen = v
            .dims
            .last()
            .map_or(1, |&d| self.schema.dims[d].len.unwrap_or(1));
        let n = l.nelems / strlen;
        if strings.len() != n {
            return Err(NcError::WrongShape {
                var: v.name.clone(),
                expected: n,
                got: strings.len(),
            });
        }
        if let Some((index, s)) = strings.iter().enumerate().find(|(_, s)| s.len() > strlen) {
            return Err(NcError::StringTooLong {
                var: v.name.clone(),
                index,
                len: s.len(),
                max: strlen,
            });
        }
        let (nbytes, begin) = (l.nbytes, l.begin);
        self.scratch.clear();
        self.scratch.resize(nbytes, 0);
        for (i, s) in strings.iter().enumerate() {
            self.scratch[i * strlen..i * strlen + s.len()].copy_from_slice(s.as_bytes());
        }
        self.write_scratch_at(begin)
    }

    fn record_slab(&self, var: VarId, got: usize) -> Result<(NcType, usize, usize), NcError> {
        let (v, l) = self.var(var)?;
        if !l.is_record {
            return Err(NcError::NotRecord(v.name.clone()));
        }
        if got != l.nelems {
            return Err(NcError::WrongShape {
                var: v.name.clone(),
                expected: l.nelems,
                got,
            });
        }
        Ok((v.ty, l.rec_off, l.nbytes))
    }

    /// Stage the values of record variable `var` for the next record (one full
    /// slab, i.e. product of its non-record dimensions). On error the slab is
    /// reset to fill values.
    pub fn set_record_f64(&mut self, var: VarId, data: &[f64]) -> Result<(), NcError> {
        let (ty, off, nbytes) = self.record_slab(var, data.len())?;
        let slab = &mut self.rec_buf[off..off + nbytes];
        let r = encode_f64(slab, ty, data, &self.schema.vars[var.0].name);
        if r.is_err() {
            slab.copy_from_slice(&self.rec_template[off..off + nbytes]);
        }
        r
    }

    /// Stage i32 values of record variable `var` for the next record.
    pub fn set_record_i32(&mut self, var: VarId, data: &[i32]) -> Result<(), NcError> {
        let (ty, off, nbytes) = self.record_slab(var, data.len())?;
        let slab = &mut self.rec_buf[off..off + nbytes];
        let r = encode_i32(slab, ty, data, &self.schema.vars[var.0].name);
        if r.is_err() {
            slab.copy_from_slice(&self.rec_template[off..off + nbytes]);
        }
        r
    }

    /// Append the staged record (unset variables get their fill value), then
    /// bump `numrecs` in the header. Does not allocate. Staging is reset to fill.
    pub fn commit_record(&mut self) -> Result<(), NcError> {
        if !self.has_record_dim {
            return Err(NcError::NoRecordDim);
        }
        if self.numrecs >= MAX_NUMRECS {
            return Err(NcError::TooManyRecords { max: MAX_NUMRECS });
        }
        if self.recsize > 0 {
            let off = self.rec_begin + self.numrecs * self.recsize as u64;
            self.file
                .write_all_at(&self.rec_buf, off)
                .map_err(|e| self.io_err(e))?;
            self.rec_buf.copy_from_slice(&self.rec_template);
        }
        let n = (self.numrecs + 1) as u32;
        self.file
            .write_all_at(&n.to_be_bytes(), 4)
            .map_err(|e| self.io_err(e))?;
        self.numrecs += 1;
        Ok(())
    }

    /// Rewrite (or add) a global attribute in place. The type of an existing
    /// attribute must not change. Data offsets never move: if the new header
    /// does not fit before the first variable's data, [`NcError::HeaderFull`]
    /// is returned and nothing is changed.
    pub fn set_global_attr(&mut self, name: &str, v: AttrValue) -> Result<(), NcError> {
        validate_name(name).map_err(NcError::Definition)?;
        let pos = self.schema.gattrs.iter().position(|(n, _)| n == name);
        let old = match pos {
            Some(i) => {
                let existing = self.schema.gattrs[i].1.nc_type();
                if existing != v.nc_type() {
                    return Err(NcError::AttrTypeMismatch {
                        name: name.to_owned(),
                        existing,
                        new: v.nc_type(),
                    });
                }
                Some(std::mem::replace(&mut self.schema.gattrs[i].1, v))
            }
            None => {
                self.schema.gattrs.push((name.to_owned(), v));
                None
            }
        };
        let mut buf = std::mem::take(&mut self.header_buf);
        self.schema
            .encode_header(self.numrecs as u32, &self.layout, &mut buf);
        if buf.len() as u64 > self.data_start {
            let needed = buf.len();
            self.header_buf = buf;
            match (pos, old) {
                (Some(i), Some(o)) => self.schema.gattrs[i].1 = o,
                _ => {
                    self.schema.gattrs.pop();
                }
            }
            return Err(NcError::HeaderFull {
                needed,
                available: self.data_start as usize,
            });
        }
        let new_len = buf.len();
        if new_len < self.header_len {
            buf.resize(self.header_len, 0); // zero the stale tail of a shrunk header
        }
        let r = self.file.write_all_at(&buf, 0);
        buf.truncate(new_len);
        self.header_buf = buf;
        r.map_err(|e| self.io_err(e))?;
        self.header_len = new_len;
        Ok(())
    }

    /// fsync data and metadata (durability against power loss); nothing for a writer in
    /// memory.
    pub fn sync(&self) -> Result<(), NcError> {
        match &self.file {
            Target::File(f) => f.sync_all().map_err(|e| self.io_err(e)),
            Target::Memory(_) => Ok(()),
        }
    }

    /// The bytes of a file written in memory ([`Definition::create_in_memory`]); `None`
    /// for a file on disk.
    pub fn into_bytes(self) -> Option<Vec<u8>> {
        match self.file {
            Target::File(_) => None,
            Target::Memory(b) => Some(b),
        }
    }

    /// Finish writing: fsync and close. Uncommitted staged values are discarded.
    pub fn finish(self) -> Result<(), NcError> {
        self.sync()
    }
}

// ---------------------------------------------------------------------------
// Tests (independent reader: the `netcdf3` crate)
// ---------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;
    use netcdf3::FileReader;

    const NREC: usize = 5;

    struct Ids {
        time: VarId,
        pos: VarId,
        iters: VarId,
        node_name: VarId,
        coords: VarId,
        conn: VarId,
    }

    fn define() -> (Definition, Ids) {
        let mut d = Definition::new();
        let t = d.add_record_dim("time");
        let node = d.add_dim("node", 3);
        let vec3 = d.add_dim("vec3", 3);
        let _quat = d.add_dim("quat", 4);
        let strlen = d.add_dim("strlen", 16);
        let time = d.add_var("time", NcType::Double, &[t]);
        d.add_var_attr(time, "units", AttrValue::Text("s".into()));
        let pos = d.add_var("position", NcType::Double, &[t, node, vec3]);
        d.add_var_attr(pos, "units", AttrValue::Text("m".into()));
        d.add_var_attr(pos, "_FillValue", AttrValue::Double(vec![f64::NAN]));
        let iters = d.add_var("iters", NcType::Int, &[t]);
        let node_name = d.add_var("node_name", NcType::Char, &[node, strlen]);
        let coords = d.add_var("coords", NcType::Double, &[node, vec3]);
        let conn = d.add_var("conn", NcType::Int, &[node]);
        d.add_var_attr(conn, "valid_range", AttrValue::Int(vec![0, 2]));
        d.add_global_attr("title", AttrValue::Text("ncwriter test".into()));
        d.add_global_attr("status", AttrValue::Text("running".into()));
        d.add_global_attr("gravity", AttrValue::Double(vec![0.0, 0.0, -9.81]));
        d.add_global_attr("n_steps", AttrValue::Int(vec![0]));
        d.reserve_header(256);
        (
            d,
            Ids {
                time,
                pos,
                iters,
                node_name,
                coords,
                conn,
            },
        )
    }

    fn pos_val(r: usize, i: usize) -> f64 {
        r as f64 * 100.0 + i as f64 * 0.5 - 1.25
    }

    fn write_fixed(w: &mut Writer, ids: &Ids) {
        w.put_fixed_text(ids.node_name, &["root", "mid", "tip_node_16chars"])
            .unwrap();
        w.put_fixed_f64(ids.coords, &[0., 0., 0., 1., 0., 0., 2., 0., 0.])
            .unwrap();
        w.put_fixed_i32(ids.conn, &[0, 1, 2]).unwrap();
    }

    fn write_records(w: &mut Writer, ids: &Ids, range: std::ops::Range<usize>) {
        let mut p = [0.0; 9];
        for r in range {
            for (i, x) in p.iter_mut().enumerate() {
                *x = pos_val(r, i);
            }
            w.set_record_f64(ids.time, &[r as f64 * 0.1]).unwrap();
            w.set_record_f64(ids.pos, &p).unwrap();
            w.set_record_i32(ids.iters, &[10 + r as i32]).unwrap();
            w.commit_record().unwrap();
        }
    }

    fn check_records(rd: &mut FileReader, n: usize) {
        assert_eq!(rd.data_set().num_records(), Some(n));
        let t = rd.read_var_f64("time").unwrap();
        assert_eq!(t, (0..n).map(|r| r as f64 * 0.1).collect::<Vec<_>>());
        let p = rd.read_var_f64("position").unwrap();
        let exp: Vec<f64> = (0..n)
            .flat_map(|r| (0..9).map(move |i| pos_val(r, i)))
            .collect();
        assert_eq!(p, exp);
        let it = rd.read_var_i32("iters").unwrap();
        assert_eq!(it, (0..n).map(|r| 10 + r as i32).collect::<Vec<_>>());
        for r in 0..n {
            let rec = rd.read_record_f64("position", r).unwrap();
            assert_eq!(rec, &exp[r * 9..r * 9 + 9]);
        }
    }

    fn check_fixed(rd: &mut FileReader) {
        let names = rd.read_var_u8("node_name").unwrap();
        let mut exp = vec![0u8; 48];
        exp[..4].copy_from_slice(b"root");
        exp[16..19].copy_from_slice(b"mid");
        exp[32..48].copy_from_slice(b"tip_node_16chars");
        assert_eq!(names, exp);
        assert_eq!(
            rd.read_var_f64("coords").unwrap(),
            vec![0., 0., 0., 1., 0., 0., 2., 0., 0.]
        );
        assert_eq!(rd.read_var_i32("conn").unwrap(), vec![0, 1, 2]);
    }

    #[test]
    fn full_roundtrip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.nc");
        let (d, ids) = define();
        let mut w = d.create(&path).unwrap();
        write_fixed(&mut w, &ids);
        write_records(&mut w, &ids, 0..NREC);
        w.set_global_attr("status", AttrValue::Text("completed".into()))
            .unwrap();
        w.set_global_attr("n_steps", AttrValue::Int(vec![NREC as i32]))
            .unwrap();
        assert_eq!(w.num_records(), NREC as u64);
        w.finish().unwrap();

        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..4], b"CDF\x02");

        let mut rd = FileReader::open(&path).unwrap();
        assert_eq!(rd.version(), netcdf3::Version::Offset64Bit);
        let ds = rd.data_set();
        assert_eq!(ds.dim_size("node"), Some(3));
        assert_eq!(ds.dim_size("vec3"), Some(3));
        assert_eq!(ds.dim_size("quat"), Some(4));
        assert_eq!(ds.dim_size("strlen"), Some(16));
        assert_eq!(ds.get_unlimited_dim().unwrap().name(), "time");
        assert_eq!(ds.var_data_type("node_name"), Some(netcdf3::DataType::U8));
        assert_eq!(ds.is_record_var("position"), Some(true));
        assert_eq!(ds.is_record_var("coords"), Some(false));
        assert_eq!(
            ds.get_var("position").unwrap().dim_names(),
            vec!["time", "node", "vec3"]
        );
        assert_eq!(
            ds.get_global_attr_as_string("title").as_deref(),
            Some("ncwriter test")
        );
        assert_eq!(
            ds.get_global_attr_as_string("status").as_deref(),
            Some("completed")
        );
        assert_eq!(
            ds.get_global_attr_f64("gravity"),
            Some(&[0.0, 0.0, -9.81][..])
        );
        assert_eq!(ds.get_global_attr_i32("n_steps"), Some(&[NREC as i32][..]));
        assert_eq!(
            ds.get_var_attr_as_string("position", "units").as_deref(),
            Some("m")
        );
        assert!(ds.get_var_attr_f64("position", "_FillValue").unwrap()[0].is_nan());
        assert_eq!(
            ds.get_var_attr_i32("conn", "valid_range"),
            Some(&[0, 2][..])
        );
        check_fixed(&mut rd);
        check_records(&mut rd, NREC);
    }

    #[test]
    fn truncated_run_keeps_committed_records() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("crash.nc");
        let (d, ids) = define();
        let mut w = d.create(&path).unwrap();
        write_fixed(&mut w, &ids);
        write_records(&mut w, &ids, 0..3);
        // Staged but never committed values must not appear.
        w.set_record_f64(ids.time, &[99.0]).unwrap();
        let recsize = w.recsize;
        drop(w); // no finish()

        let mut rd = FileReader::open(&path).unwrap();
        check_fixed(&mut rd);
        check_records(&mut rd, 3);

        // Simulate a crash in the middle of writing record 4: a partial
        // record beyond numrecs is ignored.
        let mut f = OpenOptions::new().append(true).open(&path).unwrap();
        f.write_all(&vec![0xAB; recsize / 2]).unwrap();
        drop(f);
        let mut rd = FileReader::open(&path).unwrap();
        check_records(&mut rd, 3);
    }

    #[test]
    fn create_refuses_existing_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("exists.nc");
        std::fs::write(&path, b"precious").unwrap();
        let (d, _) = define();
        match d.create(&path) {
            Err(NcError::Exists(p)) => assert_eq!(p, path),
            other => panic!("expected Exists, got {other:?}"),
        }
        assert_eq!(std::fs::read(&path).unwrap(), b"precious");
    }

    #[test]
    fn global_attr_grows_within_reserve_then_header_full() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("attr.nc");
        let (d, ids) = define();
        let mut w = d.create(&path).unwrap();
        write_fixed(&mut w, &ids);
        write_records(&mut w, &ids, 0..2);
        let fixed_begin = w.layout[ids.coords.0].begin;

        // Grow by ~200 bytes: fits in the 256 reserved bytes.
        let long = "completed: ".to_string() + &"x".repeat(190);
        w.set_global_attr("status", AttrValue::Text(long.clone()))
            .unwrap();
        // Way beyond the reserve: HeaderFull, file unchanged.
        let err = w
            .set_global_attr("status", AttrValue::Text("y".repeat(1000)))
            .unwrap_err();
        assert!(matches!(err, NcError::HeaderFull { .. }), "{err}");
        // Adding a new attribute that doesn't fit is also refused.
        let err = w
            .set_global_attr("huge", AttrValue::Double(vec![1.0; 100]))
            .unwrap_err();
        assert!(matches!(err, NcError::HeaderFull { .. }), "{err}");
        // Type change is refused.
        let err = w
            .set_global_attr("status", AttrValue::Int(vec![1]))
            .unwrap_err();
        assert!(matches!(err, NcError::AttrTypeMismatch { .. }), "{err}");
        // Records keep working after header rewrites (numrecs preserved).
        write_records(&mut w, &ids, 2..4);
        assert_eq!(w.layout[ids.coords.0].begin, fixed_begin);
        w.finish().unwrap();

        let mut rd = FileReader::open(&path).unwrap();
        assert_eq!(
            rd.data_set().get_global_attr_as_string("status"),
            Some(long)
        );
        assert!(!rd.data_set().has_global_attr("huge"));
        check_fixed(&mut rd);
        check_records(&mut rd, 4);

        // Shrinking again works and leaves a clean (zero) tail.
        let path2 = dir.path().join("attr2.nc");
        let (d, _) = define();
        let mut w = d.create(&path2).unwrap();
        w.set_global_attr("status", AttrValue::Text("z".repeat(200)))
            .unwrap();
        w.set_global_attr("status", AttrValue::Text("ok".into()))
            .unwrap();
        let hl = w.header_len;
        let ds = w.data_start as usize;
        w.finish().unwrap();
        let bytes = std::fs::read(&path2).unwrap();
        assert!(bytes[hl..ds].iter().all(|&b| b == 0));
        let rd = FileReader::open(&path2).unwrap();
        assert_eq!(
            rd.data_set().get_global_attr_as_string("status").as_deref(),
            Some("ok")
        );
    }

    #[test]
    fn zero_record_vars_and_zero_records() {
        let dir = tempfile::tempdir().unwrap();

        // Record dim, but only fixed variables; no records.
        let p1 = dir.path().join("norec.nc");
        let mut d = Definition::new();
        d.add_record_dim("time");
        let n = d.add_dim("node", 2);
        let x = d.add_var("x", NcType::Double, &[n]);
        d.add_global_attr("status", AttrValue::Text("empty".into()));
        let mut w = d.create(&p1).unwrap();
        w.put_fixed_f64(x, &[1.5, -2.5]).unwrap();
        w.finish().unwrap();
        let mut rd = FileReader::open(&p1).unwrap();
        assert_eq!(rd.data_set().num_records(), Some(0));
        assert_eq!(rd.read_var_f64("x").unwrap(), vec![1.5, -2.5]);

        // Record dim + record vars, zero records committed; unwritten fixed var = fill.
        let p2 = dir.path().join("zero.nc");
        let (d, _ids) = define();
        d.create(&p2).unwrap().finish().unwrap();
        let mut rd = FileReader::open(&p2).unwrap();
        assert_eq!(rd.data_set().num_records(), Some(0));
        assert!(rd.read_var_f64("time").unwrap().is_empty());
        assert_eq!(rd.read_var_f64("coords").unwrap(), vec![NC_FILL_DOUBLE; 9]);
        assert_eq!(rd.read_var_i32("conn").unwrap(), vec![NC_FILL_INT; 3]);

        // No dimensions, no variables at all; commit_record is an error.
        let p3 = dir.path().join("empty.nc");
        let mut d = Definition::new();
        d.add_global_attr("note", AttrValue::Text("nothing".into()));
        let mut w = d.create(&p3).unwrap();
        assert!(matches!(w.commit_record(), Err(NcError::NoRecordDim)));
        w.finish().unwrap();
        let rd = FileReader::open(&p3).unwrap();
        assert_eq!(rd.data_set().num_vars(), 0);
        assert_eq!(
            rd.data_set().get_global_attr_as_string("note").as_deref(),
            Some("nothing")
        );
    }

    #[test]
    fn unset_record_values_are_fill() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fill.nc");
        let (d, ids) = define();
        let mut w = d.create(&path).unwrap();
        w.set_record_f64(ids.time, &[1.0]).unwrap();
        w.commit_record().unwrap(); // position/iters unset
        w.finish().unwrap();
        let mut rd = FileReader::open(&path).unwrap();
        assert!(
            rd.read_var_f64("position")
                .unwrap()
                .iter()
                .all(|x| x.is_nan())
        );
        assert_eq!(rd.read_var_i32("iters").unwrap(), vec![NC_FILL_INT]);
    }

    #[test]
    fn errors_are_reported() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("err.nc");
        let (d, ids) = define();
        let mut w = d.create(&path).unwrap();
        assert!(matches!(
            w.set_record_f64(ids.pos, &[1.0; 8]),
            Err(NcError::WrongShape {
                expected: 9,
                got: 8,
                ..
            })
        ));
        assert!(matches!(
            w.put_fixed_f64(ids.pos, &[1.0; 9]),
            Err(NcError::NotFixed(_))
        ));
        assert!(matches!(
            w.set_record_f64(ids.coords, &[1.0; 9]),
            Err(NcError::NotRecord(_))
        ));
        assert!(matches!(
            w.set_record_f64(ids.iters, &[f64::NAN]),
            Err(NcError::Range { .. })
        ));
        assert!(matches!(
            w.put_fixed_text(ids.node_name, &["a", "b", "this is longer than 16"]),
            Err(NcError::StringTooLong { index: 2, .. })
        ));
        assert!(matches!(
            w.put_fixed_f64(ids.node_name, &[0.0; 48]),
            Err(NcError::TypeMismatch { .. })
        ));
        let msg = NcError::HeaderFull {
            needed: 10,
            available: 5,
        }
        .to_string();
        assert!(msg.contains("reserve_header"));

        let mut d = Definition::new();
        let t = d.add_record_dim("time");
        let n = d.add_dim("n", 2);
        d.add_record_dim("time2");
        d.add_var("bad", NcType::Double, &[n, t]);
        d.add_var("bad", NcType::Double, &[n]);
        match d.create(&dir.path().join("bad.nc")) {
            Err(NcError::Definition(m)) => {
                assert!(m.contains("only one unlimited"), "{m}");
                assert!(m.contains("first dimension"), "{m}");
                assert!(m.contains("defined twice"), "{m}");
            }
            other => panic!("{other:?}"),
        }
        assert!(!dir.path().join("bad.nc").exists());
    }

    /// Spec special case: exactly one record variable of a short type has no
    /// padding between records (recsize = 3 * 2 = 6, not 8).
    #[test]
    fn single_short_record_var_is_unpadded() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("short.nc");
        let mut d = Definition::new();
        let t = d.add_record_dim("time");
        let k = d.add_dim("k", 3);
        let s = d.add_var("s", NcType::Short, &[t, k]);
        let mut w = d.create(&path).unwrap();
        assert_eq!(w.recsize, 6);
        for r in 0..3 {
            w.set_record_i32(s, &[r, r + 10, -r]).unwrap();
            w.commit_record().unwrap();
        }
        let begin = w.layout[0].begin as usize;
        w.finish().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), begin + 18);
        let vals: Vec<i16> = bytes[begin..]
            .chunks_exact(2)
            .map(|c| i16::from_be_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(vals, vec![0, 10, 0, 1, 11, -1, 2, 12, -2]);
        let rd = FileReader::open(&path).unwrap();
        assert_eq!(rd.data_set().num_records(), Some(3));
        // (netcdf3 0.6 itself assumes padded records here, so values are checked raw; an
        // independent reader, scipy's, reads them in samara-cli/tests/python_example.rs.)
    }
}
