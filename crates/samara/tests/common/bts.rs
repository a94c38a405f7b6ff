//! A small TurbSim `.bts` writer for tests: the layout InflowWind reads
//! (`InflowWind_IO.f90`, `IfW_TurbSim_Init`): int16 id, int32 NZ, NY, tower points, NT,
//! float32 dz, dy, dt, u_hub, z_hub, z_bottom, slope/offset of u, v, w, int32 description
//! length and text, then int16 (u, v, w) per grid point (y fastest, then z) and per tower
//! point, time step after time step.
#![allow(dead_code)]

/// A box to write.
#[derive(Clone, Debug)]
pub struct Box3 {
    pub periodic: bool,
    pub ny: usize,
    pub nz: usize,
    pub nt: usize,
    pub n_tower: usize,
    pub dy: f32,
    pub dz: f32,
    pub dt: f32,
    pub mean_speed: f32,
    pub hub_height: f32,
    pub grid_bottom: f32,
    /// Slope of u, v, w (value = raw/slope + …; offsets chosen per component).
    pub slope: [f32; 3],
    pub offset: [f32; 3],
}

impl Box3 {
    /// Lateral position of column iy, height of row iz, box time of step it.
    pub fn y(&self, iy: usize) -> f64 {
        (iy as f64 - 0.5 * (self.ny - 1) as f64) * self.dy as f64
    }
    pub fn z(&self, iz: usize) -> f64 {
        self.grid_bottom as f64 + iz as f64 * self.dz as f64
    }
    pub fn t(&self, it: usize) -> f64 {
        it as f64 * self.dt as f64
    }

    /// The file bytes of the field `f(y, z, τ) → (u, v, w)` [m/s], each value rounded to
    /// the nearest int16 step of its component (error ≤ 1/(2 slope)).
    pub fn bytes(&self, f: impl Fn(f64, f64, f64) -> [f64; 3]) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend((if self.periodic { 8i16 } else { 7i16 }).to_le_bytes());
        for n in [self.nz, self.ny, self.n_tower, self.nt] {
            b.extend((n as i32).to_le_bytes());
        }
        for v in [
            self.dz,
            self.dy,
            self.dt,
            self.mean_speed,
            self.hub_height,
            self.grid_bottom,
            self.slope[0],
            self.offset[0],
            self.slope[1],
            self.offset[1],
            self.slope[2],
            self.offset[2],
        ] {
            b.extend(v.to_le_bytes());
        }
        let desc = b"written by samara's tests";
        b.extend((desc.len() as i32).to_le_bytes());
        b.extend(desc);
        let raw = |v: [f64; 3]| -> [i16; 3] {
            let mut r = [0i16; 3];
            for c in 0..3 {
                let x = (v[c] * self.slope[c] as f64 + self.offset[c] as f64).round();
                assert!(x.abs() < 32767.0, "value {} does not fit int16", v[c]);
                r[c] = x as i16;
            }
            r
        };
        for it in 0..self.nt {
            for iz in 0..self.nz {
                for iy in 0..self.ny {
                    for r in raw(f(self.y(iy), self.z(iz), self.t(it))) {
                        b.extend(r.to_le_bytes());
                    }
                }
            }
            // Tower points under the hub, from the grid's bottom row down (TurbSim's
            // placement, as openfast_toolbox reads them: z_bottom − k dz).
            for k in 0..self.n_tower {
                let z = self.grid_bottom as f64 - k as f64 * self.dz as f64;
                for r in raw(f(0.0, z.max(0.0), self.t(it))) {
                    b.extend(r.to_le_bytes());
                }
            }
        }
        b
    }
}
