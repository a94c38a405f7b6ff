//! A turbulent full-field wind read from a TurbSim binary file (`.bts`), sampled as
//! InflowWind samples it (OpenFAST, `InflowWind_IO.f90` `IfW_TurbSim_Init` and
//! `IfW_FlowField.f90` `Grid3DField_GetCell`; docs/aerodynamics.md, "Turbulent wind").
//!
//! **File layout** (little-endian): int16 format id (7 = normal, 8 = periodic); int32
//! NZ, NY, NT_tower, NT (grid points vertically, laterally, tower points, time steps);
//! float32 dz, dy, dt, u_hub (mean hub-height speed), z_hub, z_bottom (height of the grid's
//! lowest row), then slope and offset of u, v, w; int32 length of a description, its bytes;
//! then, for each time step, int16 (u, v, w) at every grid point (y fastest, then z),
//! followed by the NT_tower tower points. A value is `(raw − offset)/slope`, so int16
//! rounding errs by at most `1/(2 slope)` per component.
//!
//! **Sampling** (Taylor's frozen turbulence): in the wind frame (x along the mean wind, z
//! up, y = z × x; origin at the tower base on the ground) the grid spans
//! `y ∈ [−(NY−1)dy/2, (NY−1)dy/2]` (centred on the hub), `z ∈ [z_bottom, z_bottom +
//! (NZ−1)dz]`, and a point at x sees the box at time `τ = t + (x₀ − x)/u_hub`, x₀ half the
//! grid width for a normal file (InflowWind's start half a width ahead of the turbine) and
//! 0 for a periodic one, whose τ wraps modulo NT·dt (the step after the last sample is the
//! first). The velocity is trilinear in (y, z, τ) within the cell holding the point (the
//! eight corner values, InflowWind's `Grid3DField_GetVelLinear`). Tower points are read
//! ([`FullField::tower_value`], at heights z_bottom − k dz) and not sampled: a point below
//! the grid is an error (InflowWind interpolates to the tower points there, which a blade
//! never reaches).
//!
//! **Mean and fluctuation.** The box's time-mean at each grid point,
//! `ū(y_j, z_k) = (1/NT) Σ_i u(y_j, z_k, τ_i)` (per component), bilinear in (y, z)
//! between them ([`FullField::mean`]), is the mean wind with its shear; the rest,
//! u − ū, the turbulence (what an airfoil with Küssner's gust response takes through
//! Küssner's function, docs/aerodynamics.md).

use crate::math::dual::Scalar;
use std::sync::OnceLock;

/// Points within this fraction of a grid cell outside the grid are taken on its edge
/// (InflowWind's `GridTol`).
const GRID_TOL: f64 = 1e-3;

/// Whether grid coordinate f (in cells) lies on a grid of n points, within [`GRID_TOL`].
fn on_grid(f: f64, n: usize) -> bool {
    f >= -GRID_TOL && f <= (n - 1) as f64 + GRID_TOL
}

/// Largest grid accepted (values per time step and time steps), keeping every index and
/// byte count far inside `usize` on any platform.
const MAX_POINTS: usize = 1 << 24;

/// A .bts file that cannot be used: what is wrong, and a hint.
#[derive(Clone, Debug, PartialEq)]
pub struct BtsError {
    pub message: String,
    pub hint: String,
}

fn err(message: impl Into<String>, hint: &str) -> BtsError {
    BtsError {
        message: message.into(),
        hint: hint.into(),
    }
}

/// The wind box of a TurbSim file.
pub struct FullField {
    /// Where the box was read from (for messages).
    pub source: String,
    /// Whether the file is periodic in time (format id 8).
    pub periodic: bool,
    /// Grid points laterally and vertically, tower points, time steps.
    pub ny: usize,
    pub nz: usize,
    pub n_tower: usize,
    pub nt: usize,
    /// Grid spacings [m] and time step [s].
    pub dy: f64,
    pub dz: f64,
    pub dt: f64,
    /// Mean hub-height speed u_hub [m/s] (the speed the box advances at).
    pub mean_speed: f64,
    /// Hub height and height of the grid's lowest row [m].
    pub hub_height: f64,
    pub grid_bottom: f64,
    /// Slope and offset of u, v, w: value = (raw − offset)/slope.
    pub slope: [f64; 3],
    pub offset: [f64; 3],
    /// The file's description text.
    pub description: String,
    /// Raw samples (u, v, w) at (t, z, y), y fastest.
    raw: Vec<[i16; 3]>,
    /// Raw tower samples (u, v, w) at (t, k), k fastest.
    tower_raw: Vec<[i16; 3]>,
    /// Time-mean (u, v, w) at each grid point (z, y), y fastest [m/s].
    mean: Vec<[f64; 3]>,
    /// The first sample taken outside the box (a runtime error, reported by the analysis).
    outside: OnceLock<String>,
}

impl std::fmt::Debug for FullField {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "FullField {{ {}×{} grid, {} steps of {} s, dy {} m, dz {} m, u_hub {} m/s, z_hub {} m, bottom {} m, periodic {} }}",
            self.ny,
            self.nz,
            self.nt,
            self.dt,
            self.dy,
            self.dz,
            self.mean_speed,
            self.hub_height,
            self.grid_bottom,
            self.periodic
        )
    }
}

/// Little-endian reader over a byte slice, failing on truncation.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, what: &str) -> Result<&[u8], BtsError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(err(
                format!(
                    "the file ends at byte {} while reading {what} (a TurbSim .bts file is longer)",
                    self.bytes.len()
                ),
                "the file is truncated or not a TurbSim binary full-field file",
            ));
        };
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn i16(&mut self, what: &str) -> Result<i16, BtsError> {
        let b = self.take(2, what)?;
        Ok(i16::from_le_bytes([b[0], b[1]]))
    }
    fn i32(&mut self, what: &str) -> Result<i32, BtsError> {
        let b = self.take(4, what)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn f32(&mut self, what: &str) -> Result<f64, BtsError> {
        let b = self.take(4, what)?;
        Ok(f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
    }
}

impl FullField {
    /// Parses the bytes of a .bts file.
    pub fn parse(bytes: &[u8]) -> Result<Self, BtsError> {
        let mut r = Reader { bytes, at: 0 };
        let id = r.i16("the format id")?;
        let periodic = match id {
            7 => false,
            8 => true,
            _ => {
                return Err(err(
                    format!(
                        "format id {id}: a TurbSim binary full-field file starts with 7 (normal) or 8 (periodic)"
                    ),
                    "give a TurbSim `.bts` file (WrBLFF output of TurbSim)",
                ));
            }
        };
        let count = |r: &mut Reader, what: &str, min: i32| -> Result<usize, BtsError> {
            let n = r.i32(what)?;
            if n < min || n as usize > MAX_POINTS {
                return Err(err(
                    format!("{what} = {n} must be {min} … {MAX_POINTS}"),
                    "the header is corrupt or the file is not a TurbSim .bts file",
                ));
            }
            Ok(n as usize)
        };
        let nz = count(&mut r, "NZ (grid points vertically)", 2)?;
        let ny = count(&mut r, "NY (grid points laterally)", 2)?;
        let n_tower = count(&mut r, "the number of tower points", 0)?;
        let nt = count(&mut r, "NT (time steps)", 2)?;
        let mut real = |what: &str, positive: bool| -> Result<f64, BtsError> {
            let v = r.f32(what)?;
            if !v.is_finite() || (positive && v <= 0.0) {
                let bound = if positive { "finite and > 0" } else { "finite" };
                return Err(err(
                    format!("{what} = {v} must be {bound}"),
                    "the header is corrupt or the file is not a TurbSim .bts file",
                ));
            }
            Ok(v)
        };
        let dz = real("dz", true)?;
        let dy = real("dy", true)?;
        let dt = real("dt", true)?;
        let mean_speed = real("the mean hub-height speed", true)?;
        let hub_height = real("the hub height", false)?;
        let grid_bottom = real("the grid-bottom height", false)?;
        let mut slope = [0.0; 3];
        let mut offset = [0.0; 3];
        for (k, c) in ["u", "v", "w"].iter().enumerate() {
            slope[k] = real(&format!("the {c} slope"), false)?;
            offset[k] = real(&format!("the {c} offset"), false)?;
            if slope[k] == 0.0 {
                return Err(err(
                    format!("the {c} slope is 0 (values are (raw − offset)/slope)"),
                    "the header is corrupt or the file is not a TurbSim .bts file",
                ));
            }
        }
        let n_desc = r.i32("the description length")?;
        let n_desc = usize::try_from(n_desc).map_err(|_| {
            err(
                format!("the description length {n_desc} is negative"),
                "the header is corrupt or the file is not a TurbSim .bts file",
            )
        })?;
        let description = String::from_utf8_lossy(r.take(n_desc, "the description")?)
            .trim()
            .to_string();
        let overflow = || {
            err(
                format!("the grid ({ny} × {nz} + {n_tower} tower points, {nt} steps) is too large"),
                "the header is corrupt or the file is not a TurbSim .bts file",
            )
        };
        let per_step = ny
            .checked_mul(nz)
            .and_then(|g| g.checked_add(n_tower))
            .filter(|&p| p <= MAX_POINTS)
            .ok_or_else(overflow)?;
        let points = per_step.checked_mul(nt).ok_or_else(overflow)?;
        let expected = points.checked_mul(6).ok_or_else(overflow)?;
        let left = bytes.len() - r.at;
        if left != expected {
            return Err(err(
                format!(
                    "the header announces {nt} steps of {ny} × {nz} grid and {n_tower} tower points ({expected} bytes of samples) but {left} bytes follow it"
                ),
                "the file is truncated or not a TurbSim binary full-field file",
            ));
        }
        let grid = ny * nz;
        let mut raw = Vec::with_capacity(grid * nt);
        let mut tower_raw = Vec::with_capacity(n_tower * nt);
        for _ in 0..nt {
            for k in 0..per_step {
                let mut v = [0i16; 3];
                for c in &mut v {
                    *c = r.i16("a sample")?;
                }
                if k < grid {
                    raw.push(v);
                } else {
                    tower_raw.push(v);
                }
            }
        }
        // Time means: Σ raw per point, then (Σ/NT − offset)/slope.
        let mut sum = vec![[0.0f64; 3]; grid];
        for step in raw.chunks_exact(grid) {
            for (s, v) in sum.iter_mut().zip(step) {
                for c in 0..3 {
                    s[c] += v[c] as f64;
                }
            }
        }
        let mean = sum
            .iter()
            .map(|s| std::array::from_fn(|c| (s[c] / nt as f64 - offset[c]) / slope[c]))
            .collect();
        Ok(Self {
            source: String::new(),
            periodic,
            ny,
            nz,
            n_tower,
            nt,
            dy,
            dz,
            dt,
            mean_speed,
            hub_height,
            grid_bottom,
            slope,
            offset,
            description,
            raw,
            tower_raw,
            mean,
            outside: OnceLock::new(),
        })
    }

    /// Half the grid width (NY−1)dy/2 [m].
    pub fn half_width(&self) -> f64 {
        0.5 * (self.ny - 1) as f64 * self.dy
    }

    /// Height of the grid's top row [m].
    pub fn grid_top(&self) -> f64 {
        self.grid_bottom + (self.nz - 1) as f64 * self.dz
    }

    /// Time span of the box [s]: (NT−1)dt, or NT·dt for a periodic file (its period).
    pub fn span(&self) -> f64 {
        let n = if self.periodic { self.nt } else { self.nt - 1 };
        n as f64 * self.dt
    }

    /// x₀: where the box's first time slice is at t = 0 (half the width for a normal file).
    pub fn start_x(&self) -> f64 {
        if self.periodic {
            0.0
        } else {
            self.half_width()
        }
    }

    /// The box time τ = t + (x₀ − x)/u_hub a point at x sees at time t (not wrapped).
    pub fn box_time<S: Scalar>(&self, x: S, t: f64) -> S {
        (S::cst(self.start_x()) - x) / self.mean_speed + t
    }

    /// The stored value of component c at time step it, row iz, column iy [m/s].
    pub fn value(&self, it: usize, iz: usize, iy: usize, c: usize) -> f64 {
        self.decode(&self.raw[(it * self.nz + iz) * self.ny + iy], c)
    }

    /// Component c of a stored sample [m/s]: (raw − offset)/slope.
    #[inline(always)]
    fn decode(&self, raw: &[i16; 3], c: usize) -> f64 {
        (raw[c] as f64 - self.offset[c]) / self.slope[c]
    }

    /// The stored value of component c at time step it, tower point k (height
    /// z_bottom − k dz, k = 0 at the grid's bottom row, as openfast_toolbox's reader places
    /// them) [m/s].
    pub fn tower_value(&self, it: usize, k: usize, c: usize) -> f64 {
        self.decode(&self.tower_raw[it * self.n_tower + k], c)
    }

    /// Height of tower point k [m].
    pub fn tower_height(&self, k: usize) -> f64 {
        self.grid_bottom - k as f64 * self.dz
    }

    /// The time-mean (u, v, w) [m/s] at lateral position y and height z, bilinear between
    /// the grid points' means; `None` outside the grid.
    pub fn mean<S: Scalar>(&self, y: S, z: S) -> Option<[S; 3]> {
        if self.outside(y.re(), z.re(), 0.0).is_some() {
            return None;
        }
        let (iy, xy) = Self::cell((y + self.half_width()) / self.dy, self.ny);
        let (iz, xz) = Self::cell((z - self.grid_bottom) / self.dz, self.nz);
        let one = S::cst(1.0);
        let wy = [one - xy, xy];
        let wz = [one - xz, xz];
        let mut out = [S::cst(0.0); 3];
        for (kz, &wzk) in wz.iter().enumerate() {
            for (ky, &wyk) in wy.iter().enumerate() {
                let w = wzk * wyk;
                let m = &self.mean[(iz + kz) * self.ny + iy + ky];
                for (o, &mc) in out.iter_mut().zip(m) {
                    *o += w * mc;
                }
            }
        }
        Some(out)
    }

    /// Whether grid coordinates fy, fz (in cells) and box time τ are inside the box: the
    /// tests of [`Self::outside`], without its messages.
    fn in_box(&self, fy: f64, fz: f64, tau: f64) -> bool {
        let ft = tau / self.dt;
        on_grid(fy, self.ny)
            && on_grid(fz, self.nz)
            && (self.periodic || on_grid(ft, self.nt))
            && ft.is_finite()
    }

    /// Why (y, z, τ) is outside the box, if it is.
    pub fn outside(&self, y: f64, z: f64, tau: f64) -> Option<String> {
        let hw = self.half_width();
        let fy = (y + hw) / self.dy;
        let fz = (z - self.grid_bottom) / self.dz;
        if !on_grid(fy, self.ny) {
            return Some(format!(
                "lateral position y = {y:.4} m is outside the grid's −{hw:.4} … {hw:.4} m"
            ));
        }
        if !on_grid(fz, self.nz) {
            return Some(format!(
                "height z = {z:.4} m is outside the grid's {:.4} … {:.4} m",
                self.grid_bottom,
                self.grid_top()
            ));
        }
        let ft = tau / self.dt;
        let in_time = on_grid(ft, self.nt);
        if !self.periodic && !in_time {
            return Some(format!(
                "box time τ = {tau:.4} s is outside the file's 0 … {:.4} s",
                self.span()
            ));
        }
        if !ft.is_finite() {
            return Some(format!("box time τ = {tau} s is not finite"));
        }
        None
    }

    /// Records the first sample outside the box (`what` names it).
    pub fn record_outside(&self, what: String) {
        let _ = self.outside.set(what);
    }

    /// The first sample taken outside the box, if any.
    pub fn outside_sample(&self) -> Option<&str> {
        self.outside.get().map(|s| s.as_str())
    }

    /// Cell index and local coordinate ξ ∈ [0, 1] of a grid coordinate f (in cells) on
    /// n points, clamped onto the edge cells within the tolerance.
    fn cell<S: Scalar>(f: S, n: usize) -> (usize, S) {
        let i = (f.re().floor().max(0.0) as usize).min(n - 2);
        (i, f - i as f64)
    }

    /// (u, v, w) [m/s] at lateral position y, height z and box time τ, trilinear in the
    /// cell; `None` outside the box.
    pub fn sample<S: Scalar>(&self, y: S, z: S, tau: S) -> Option<[S; 3]> {
        let fy = (y + self.half_width()) / self.dy;
        let fz = (z - self.grid_bottom) / self.dz;
        if !self.in_box(fy.re(), fz.re(), tau.re()) {
            return None;
        }
        let (iy, xy) = Self::cell(fy, self.ny);
        let (iz, xz) = Self::cell(fz, self.nz);
        let (it0, it1, xt) = if self.periodic {
            let period = self.span();
            let wraps = (tau.re() / period).floor();
            let f = (tau - wraps * period) / self.dt;
            let i = (f.re().floor().max(0.0) as usize).min(self.nt - 1);
            (i, (i + 1) % self.nt, f - i as f64)
        } else {
            let (i, x) = Self::cell(tau / self.dt, self.nt);
            (i, i + 1, x)
        };
        let one = S::cst(1.0);
        let wy = [one - xy, xy];
        let wz = [one - xz, xz];
        let wt = [one - xt, xt];
        let mut out = [S::cst(0.0); 3];
        for (kt, it) in [it0, it1].into_iter().enumerate() {
            for (kz, &wzk) in wz.iter().enumerate() {
                // The two columns iy, iy + 1 of row iz + kz at step it.
                let at = (it * self.nz + iz + kz) * self.ny + iy;
                let pair = &self.raw[at..at + 2];
                for (&wyk, v) in wy.iter().zip(pair) {
                    let w = wt[kt] * wzk * wyk;
                    for (c, o) in out.iter_mut().enumerate() {
                        *o += w * self.decode(v, c);
                    }
                }
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file of the given header and samples (raw values), little-endian.
    fn bts(
        id: i16,
        ny: i32,
        nz: i32,
        nt: i32,
        f: impl Fn(usize, usize, usize) -> [i16; 3],
    ) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend(id.to_le_bytes());
        for n in [nz, ny, 0, nt] {
            b.extend(n.to_le_bytes());
        }
        for v in [
            2.0f32, 3.0, 0.5, 10.0, 90.0, 87.0, 100.0, 0.0, 200.0, 0.0, 400.0, 0.0,
        ] {
            b.extend(v.to_le_bytes());
        }
        b.extend(4i32.to_le_bytes());
        b.extend(b"test");
        for it in 0..nt as usize {
            for iz in 0..nz as usize {
                for iy in 0..ny as usize {
                    for v in f(it, iz, iy) {
                        b.extend(v.to_le_bytes());
                    }
                }
            }
        }
        b
    }

    #[test]
    fn trilinear_in_the_cell_and_periodic_wrap() {
        // u = it + 2 iz + 3 iy (raw/100), exactly trilinear.
        let b = bts(8, 3, 4, 5, |it, iz, iy| {
            [(100 * (it + 2 * iz + 3 * iy)) as i16, 0, 0]
        });
        let f = FullField::parse(&b).unwrap();
        assert_eq!((f.ny, f.nz, f.nt, f.periodic), (3, 4, 5, true));
        assert_eq!(f.description, "test");
        // y = −3 + 1.5 (iy 0.5), z = 87 + 3 (iz 1.5), τ = 0.75 (it 1.5).
        let u = f.sample(-1.5, 90.0, 0.75).unwrap()[0];
        assert!((u - (1.5 + 3.0 + 1.5)).abs() < 1e-12, "{u}");
        // The last interval wraps to the first sample: τ = 4.5 dt halfway 4 → 0.
        let u = f.sample(-3.0, 87.0, 2.25).unwrap()[0];
        assert!((u - 2.0).abs() < 1e-12, "{u}");
        // One period later, the same.
        let u2 = f.sample(-3.0, 87.0, 2.25 + 2.5).unwrap()[0];
        assert!((u2 - u).abs() < 1e-12);
    }

    #[test]
    fn time_mean_is_the_average_of_the_steps_bilinear_in_space() {
        // u = it + 2 iz + 3 iy (raw/100): over it = 0 … 4 the mean is 2 + 2 iz + 3 iy.
        let b = bts(7, 3, 4, 5, |it, iz, iy| {
            [(100 * (it + 2 * iz + 3 * iy)) as i16, 50, -100]
        });
        let f = FullField::parse(&b).unwrap();
        // iy 0.5, iz 1.5 (as above).
        let m = f.mean(-1.5, 90.0).unwrap();
        let want = [2.0 + 3.0 + 1.5, 50.0 / 200.0, -100.0 / 400.0];
        for c in 0..3 {
            assert!((m[c] - want[c]).abs() < 1e-12, "{m:?}");
        }
        assert!(f.mean(-1.5, 86.0).is_none());
    }

    #[test]
    fn bad_files() {
        let good = bts(7, 2, 2, 2, |_, _, _| [0, 0, 0]);
        assert!(FullField::parse(&good).is_ok());
        let mut b = good.clone();
        b[0] = 9;
        assert!(
            FullField::parse(&b)
                .unwrap_err()
                .message
                .contains("format id 9")
        );
        let e = FullField::parse(&good[..good.len() - 1]).unwrap_err();
        assert!(e.message.contains("bytes follow"), "{}", e.message);
        let e = FullField::parse(&good[..20]).unwrap_err();
        assert!(e.message.contains("ends at byte 20"), "{}", e.message);
        // Sizes whose product overflows.
        let mut b = good.clone();
        b[2..6].copy_from_slice(&(i32::MAX).to_le_bytes());
        assert!(FullField::parse(&b).is_err());
        let mut b = good;
        b[2..6].copy_from_slice(&(1i32 << 23).to_le_bytes());
        b[6..10].copy_from_slice(&(1i32 << 23).to_le_bytes());
        assert!(
            FullField::parse(&b)
                .unwrap_err()
                .message
                .contains("too large")
        );
    }
}
