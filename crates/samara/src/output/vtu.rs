//! A VTK XML UnstructuredGrid (`.vtu`) file with binary data: every array is stored
//! inline as `format="binary"`, the base64 encoding of its byte count (a little-endian
//! `UInt64`, `header_type="UInt64"`) followed by its little-endian values, as the VTK
//! file-format specification ("VTK XML formats", binary data) describes. Read by VTK,
//! ParaView, meshio and vtkio. (Raw appended data would be a third smaller, but raw bytes
//! inside XML are not read by every XML-based reader.)

use std::fmt::Write as _;

/// VTK cell types used here.
pub const VTK_VERTEX: u8 = 1;
pub const VTK_POLY_LINE: u8 = 4;
pub const VTK_HEXAHEDRON: u8 = 12;

/// The values of one data array.
pub enum Values {
    F64(Vec<f64>),
    I32(Vec<i32>),
}

struct Array {
    name: String,
    components: usize,
    values: Values,
}

/// One piece of an unstructured grid, built cell by cell.
#[derive(Default)]
pub struct Grid {
    /// Point coordinates, 3 per point.
    pub points: Vec<f64>,
    connectivity: Vec<i64>,
    offsets: Vec<i64>,
    types: Vec<u8>,
    point_data: Vec<Array>,
    cell_data: Vec<Array>,
}

impl Grid {
    pub fn n_points(&self) -> usize {
        self.points.len() / 3
    }

    pub fn n_cells(&self) -> usize {
        self.types.len()
    }

    /// Adds a point and returns its index.
    pub fn add_point(&mut self, x: [f64; 3]) -> usize {
        self.points.extend(x);
        self.n_points() - 1
    }

    /// Adds a cell of `kind` through the points `ids`.
    pub fn add_cell(&mut self, kind: u8, ids: &[usize]) {
        self.connectivity.extend(ids.iter().map(|&i| i as i64));
        self.offsets.push(self.connectivity.len() as i64);
        self.types.push(kind);
    }

    /// Point data: `components` values per point.
    pub fn point_data(&mut self, name: &str, components: usize, values: Values) {
        self.point_data.push(Array {
            name: name.into(),
            components,
            values,
        });
    }

    /// Cell data: `components` values per cell.
    pub fn cell_data(&mut self, name: &str, components: usize, values: Values) {
        self.cell_data.push(Array {
            name: name.into(),
            components,
            values,
        });
    }

    /// The whole file.
    pub fn to_bytes(&self) -> Vec<u8> {
        use base64::Engine as _;
        let mut xml = String::new();
        let array = |xml: &mut String, ty: &str, name: &str, comps: usize, bytes: Vec<u8>| {
            let mut block = Vec::with_capacity(8 + bytes.len());
            block.extend((bytes.len() as u64).to_le_bytes());
            block.extend(bytes);
            let _ = write!(
                xml,
                "        <DataArray type=\"{ty}\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"binary\">\n          "
            );
            base64::engine::general_purpose::STANDARD.encode_string(&block, xml);
            xml.push_str("\n        </DataArray>\n");
        };
        let f64s = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let i64s = |v: &[i64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
        let _ = write!(
            xml,
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n      <Points>\n",
            self.n_points(),
            self.n_cells()
        );
        array(&mut xml, "Float64", "Points", 3, f64s(&self.points));
        xml.push_str("      </Points>\n      <Cells>\n");
        array(
            &mut xml,
            "Int64",
            "connectivity",
            1,
            i64s(&self.connectivity),
        );
        array(&mut xml, "Int64", "offsets", 1, i64s(&self.offsets));
        array(&mut xml, "UInt8", "types", 1, self.types.clone());
        xml.push_str("      </Cells>\n");
        for (tag, arrays) in [
            ("PointData", &self.point_data),
            ("CellData", &self.cell_data),
        ] {
            let _ = writeln!(xml, "      <{tag}>");
            for a in arrays.iter() {
                let bytes = match &a.values {
                    Values::F64(v) => f64s(v),
                    Values::I32(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
                };
                let ty = match &a.values {
                    Values::F64(_) => "Float64",
                    Values::I32(_) => "Int32",
                };
                array(&mut xml, ty, &a.name, a.components, bytes);
            }
            let _ = writeln!(xml, "      </{tag}>");
        }
        xml.push_str("    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n");
        xml.into_bytes()
    }
}
