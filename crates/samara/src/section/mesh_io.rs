//! Mesh files: samara's small text format and Gmsh's `.msh` version 4 (ASCII).
//!
//! The text format (`#` starts a comment; blank lines are ignored):
//!
//! ```text
//! nodes
//! # id   y [m]   z [m]
//! 1      0.0     0.0
//! …
//! elements
//! # id  type   region  node ids (Gmsh order: corners counter-clockwise, then mid-sides)
//! 1     quad8  skin    1 2 3 4 5 6 7 8
//! ```
//!
//! Types: `tri3`, `tri6`, `quad4`, `quad8`, `quad9`. The region names an entry of the
//! section file's `[[mesh.regions]]` (material and angles). In a Gmsh file the regions are
//! the physical groups of the 2-D elements (by name, or by number when unnamed); mesh
//! coordinates (x, y) become the section's (y, z). Only 2-D elements are read (types 2, 3,
//! 9, 10, 16); nodes that no 2-D element uses are dropped.
//!
//! Every error carries the byte range in the file of what is wrong.

use super::element::{ElementKind, MAX_NODES};
use std::collections::HashMap;
use std::ops::Range;

/// A 2-D element as read from a Gmsh file: type, (node tag, where) pairs, entity, where.
type RawElement = (ElementKind, Vec<(usize, Range<usize>)>, usize, Range<usize>);

/// A mesh as read from a file: elements carry their region's name; materials and angles
/// are assigned from the regions later.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshFile {
    pub nodes: Vec<[f64; 2]>,
    pub elements: Vec<FileElement>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct FileElement {
    pub kind: ElementKind,
    pub nodes: [usize; MAX_NODES],
    pub region: String,
    /// Where the element is written in the file.
    pub span: Range<usize>,
}

/// A located error in a mesh file.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFileError {
    pub span: Range<usize>,
    pub message: String,
    pub hint: Option<String>,
}

fn err(span: Range<usize>, message: impl Into<String>, hint: Option<&str>) -> MeshFileError {
    MeshFileError {
        span,
        message: message.into(),
        hint: hint.map(str::to_string),
    }
}

/// Whitespace-separated tokens of a text with their byte ranges, line by line.
struct Tokens<'a> {
    text: &'a str,
    lines: Vec<(usize, Vec<Range<usize>>)>,
    at: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, comment: Option<char>) -> Self {
        let mut lines = Vec::new();
        let mut start = 0;
        for line in text.split_inclusive('\n') {
            let body = match comment.and_then(|c| line.find(c)) {
                Some(i) => &line[..i],
                None => line,
            };
            let mut toks = Vec::new();
            let mut pos = 0;
            for w in body.split_whitespace() {
                let off = body[pos..].find(w).expect("token") + pos;
                toks.push(start + off..start + off + w.len());
                pos = off + w.len();
            }
            if !toks.is_empty() {
                lines.push((start, toks));
            }
            start += line.len();
        }
        Self { text, lines, at: 0 }
    }

    fn peek(&self) -> Option<&(usize, Vec<Range<usize>>)> {
        self.lines.get(self.at)
    }

    fn next_line(&mut self) -> Option<(usize, Vec<Range<usize>>)> {
        let l = self.lines.get(self.at).cloned();
        self.at += 1;
        l
    }

    fn word(&self, r: &Range<usize>) -> &'a str {
        &self.text[r.clone()]
    }

    fn end_span(&self) -> Range<usize> {
        let n = self.text.len();
        n.saturating_sub(1)..n
    }
}

fn parse_f64(t: &Tokens, r: &Range<usize>, what: &str) -> Result<f64, MeshFileError> {
    match t.word(r).parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(err(
            r.clone(),
            format!("expected {what} (a finite number), found '{}'", t.word(r)),
            None,
        )),
    }
}

fn parse_usize(t: &Tokens, r: &Range<usize>, what: &str) -> Result<usize, MeshFileError> {
    t.word(r).parse::<usize>().map_err(|_| {
        err(
            r.clone(),
            format!(
                "expected {what} (a non-negative integer), found '{}'",
                t.word(r)
            ),
            None,
        )
    })
}

/// Reads samara's text mesh format.
pub fn read_text(text: &str) -> Result<MeshFile, MeshFileError> {
    let mut t = Tokens::new(text, Some('#'));
    let mut ids: HashMap<usize, usize> = HashMap::new();
    let mut out = MeshFile::default();
    let hint_nodes =
        Some("the file starts with a line `nodes`, then `id y z` per node, then a line `elements`");
    match t.next_line() {
        Some((_, toks)) if toks.len() == 1 && t.word(&toks[0]) == "nodes" => {}
        Some((_, toks)) => {
            return Err(err(
                toks[0].clone(),
                "expected the section header `nodes`",
                hint_nodes,
            ));
        }
        None => return Err(err(t.end_span(), "the mesh file is empty", hint_nodes)),
    }
    loop {
        let Some((_, toks)) = t.next_line() else {
            return Err(err(
                t.end_span(),
                "missing the `elements` section",
                hint_nodes,
            ));
        };
        if toks.len() == 1 && t.word(&toks[0]) == "elements" {
            break;
        }
        if toks.len() != 3 {
            return Err(err(
                toks[0].start..toks.last().expect("token").end,
                format!("a node line has 3 values (id y z), found {}", toks.len()),
                hint_nodes,
            ));
        }
        let id = parse_usize(&t, &toks[0], "a node id")?;
        let y = parse_f64(&t, &toks[1], "the y coordinate")?;
        let z = parse_f64(&t, &toks[2], "the z coordinate")?;
        if ids.insert(id, out.nodes.len()).is_some() {
            return Err(err(
                toks[0].clone(),
                format!("node {id} is defined twice"),
                None,
            ));
        }
        out.nodes.push([y, z]);
    }
    let mut elem_ids: HashMap<usize, ()> = HashMap::new();
    let hint_el = Some(
        "an element line is `id type region n1 n2 …` with type tri3, tri6, quad4, quad8 or quad9",
    );
    while let Some((_, toks)) = t.next_line() {
        if toks.len() < 3 {
            return Err(err(
                toks[0].start..toks.last().expect("token").end,
                "an element line needs an id, a type, a region and its nodes",
                hint_el,
            ));
        }
        let id = parse_usize(&t, &toks[0], "an element id")?;
        if elem_ids.insert(id, ()).is_some() {
            return Err(err(
                toks[0].clone(),
                format!("element {id} is defined twice"),
                None,
            ));
        }
        let kind = ElementKind::from_name(t.word(&toks[1])).ok_or_else(|| {
            err(
                toks[1].clone(),
                format!("unknown element type '{}'", t.word(&toks[1])),
                hint_el,
            )
        })?;
        let nn = kind.n_nodes();
        if toks.len() != 3 + nn {
            return Err(err(
                toks[0].start..toks.last().expect("token").end,
                format!(
                    "a {} element has {nn} nodes, this line lists {}",
                    kind.name(),
                    toks.len() - 3
                ),
                hint_el,
            ));
        }
        let mut nodes = [0; MAX_NODES];
        for (k, r) in toks[3..].iter().enumerate() {
            let nid = parse_usize(&t, r, "a node id")?;
            nodes[k] = *ids
                .get(&nid)
                .ok_or_else(|| err(r.clone(), format!("node {nid} is not defined"), None))?;
        }
        out.elements.push(FileElement {
            kind,
            nodes,
            region: t.word(&toks[2]).to_string(),
            span: toks[0].start..toks.last().expect("token").end,
        });
    }
    if out.elements.is_empty() {
        return Err(err(t.end_span(), "the mesh has no elements", hint_el));
    }
    Ok(out)
}

/// Gmsh element type → our element (2-D types only).
fn gmsh_kind(t: usize) -> Option<ElementKind> {
    Some(match t {
        2 => ElementKind::Tri3,
        3 => ElementKind::Quad4,
        9 => ElementKind::Tri6,
        10 => ElementKind::Quad9,
        16 => ElementKind::Quad8,
        _ => return None,
    })
}

/// Number of nodes of a Gmsh element type (those that can appear next to 2-D meshes).
fn gmsh_nodes(t: usize) -> Option<usize> {
    Some(match t {
        15 => 1,
        1 => 2,
        8 => 3,
        2 => 3,
        3 => 4,
        9 => 6,
        10 => 9,
        16 => 8,
        4 => 4,
        11 => 10,
        5 => 8,
        6 => 6,
        7 => 5,
        17 => 20,
        12 => 27,
        18 => 15,
        13 => 18,
        14 => 14,
        19 => 13,
        _ => return None,
    })
}

/// Reads a Gmsh `.msh` file, format 4.x ASCII.
pub fn read_gmsh(text: &str) -> Result<MeshFile, MeshFileError> {
    let mut t = Tokens::new(text, None);
    let hint =
        Some("export the mesh from Gmsh as version 4 ASCII (File › Export, or -format msh4)");
    let mut physical_names: HashMap<(usize, usize), String> = HashMap::new();
    // Physical tags of the surface entities.
    let mut surface_physical: HashMap<usize, Vec<usize>> = HashMap::new();
    let mut node_index: HashMap<usize, usize> = HashMap::new();
    let mut coords: Vec<[f64; 2]> = Vec::new();
    let mut raw_elements: Vec<RawElement> = Vec::new();
    let mut seen_format = false;
    while let Some((_, toks)) = t.next_line() {
        let head = t.word(&toks[0]);
        match head {
            "$MeshFormat" => {
                let (_, v) = t
                    .next_line()
                    .ok_or_else(|| err(t.end_span(), "truncated $MeshFormat", hint))?;
                let ver = t.word(&v[0]);
                if !ver.starts_with('4') {
                    return Err(err(
                        v[0].clone(),
                        format!("Gmsh format version {ver} is not supported"),
                        hint,
                    ));
                }
                if v.len() < 2 || t.word(&v[1]) != "0" {
                    return Err(err(
                        v[0].start..v.last().expect("token").end,
                        "binary .msh files are not supported",
                        hint,
                    ));
                }
                seen_format = true;
                skip_to(&mut t, "$EndMeshFormat")?;
            }
            "$PhysicalNames" => {
                let (_, n) = t
                    .next_line()
                    .ok_or_else(|| err(t.end_span(), "truncated $PhysicalNames", hint))?;
                let count = parse_usize(&t, &n[0], "the number of physical names")?;
                for _ in 0..count {
                    let (_, l) = t
                        .next_line()
                        .ok_or_else(|| err(t.end_span(), "truncated $PhysicalNames", hint))?;
                    if l.len() < 3 {
                        return Err(err(
                            l[0].clone(),
                            "a physical name line is `dim tag \"name\"`",
                            hint,
                        ));
                    }
                    let dim = parse_usize(&t, &l[0], "a dimension")?;
                    let tag = parse_usize(&t, &l[1], "a physical tag")?;
                    let name = t.text[l[2].start..l.last().expect("token").end]
                        .trim_matches('"')
                        .to_string();
                    physical_names.insert((dim, tag), name);
                }
                skip_to(&mut t, "$EndPhysicalNames")?;
            }
            "$Entities" => {
                let (_, n) = t
                    .next_line()
                    .ok_or_else(|| err(t.end_span(), "truncated $Entities", hint))?;
                if n.len() < 4 {
                    return Err(err(
                        n[0].clone(),
                        "expected the entity counts `points curves surfaces volumes`",
                        hint,
                    ));
                }
                let counts: Vec<usize> = n[..4]
                    .iter()
                    .map(|r| parse_usize(&t, r, "an entity count"))
                    .collect::<Result<_, _>>()?;
                for (dim, &count) in counts.iter().enumerate() {
                    for _ in 0..count {
                        let (_, l) = t
                            .next_line()
                            .ok_or_else(|| err(t.end_span(), "truncated $Entities", hint))?;
                        if dim == 2 {
                            // tag minX minY minZ maxX maxY maxZ numPhysical tags… …
                            if l.len() < 8 {
                                return Err(err(
                                    l[0].clone(),
                                    "a surface entity line is too short",
                                    hint,
                                ));
                            }
                            let tag = parse_usize(&t, &l[0], "an entity tag")?;
                            let np = parse_usize(&t, &l[7], "the number of physical tags")?;
                            let mut phys = Vec::new();
                            for r in l.iter().skip(8).take(np) {
                                let v: i64 = t
                                    .word(r)
                                    .parse()
                                    .map_err(|_| err(r.clone(), "expected a physical tag", hint))?;
                                phys.push(v.unsigned_abs() as usize);
                            }
                            surface_physical.insert(tag, phys);
                        }
                    }
                }
                skip_to(&mut t, "$EndEntities")?;
            }
            "$Nodes" => {
                let (_, n) = t
                    .next_line()
                    .ok_or_else(|| err(t.end_span(), "truncated $Nodes", hint))?;
                if n.len() < 2 {
                    return Err(err(
                        n[0].clone(),
                        "expected `numEntityBlocks numNodes minTag maxTag`",
                        hint,
                    ));
                }
                let blocks = parse_usize(&t, &n[0], "the number of node blocks")?;
                for _ in 0..blocks {
                    let (_, b) = t
                        .next_line()
                        .ok_or_else(|| err(t.end_span(), "truncated $Nodes", hint))?;
                    if b.len() < 4 {
                        return Err(err(
                            b[0].clone(),
                            "a node block header is `dim tag parametric count`",
                            hint,
                        ));
                    }
                    parse_usize(&t, &b[2], "the parametric flag")?;
                    let count = parse_usize(&t, &b[3], "the number of nodes in the block")?;
                    let mut tags = Vec::new();
                    for _ in 0..count {
                        let (_, l) = t
                            .next_line()
                            .ok_or_else(|| err(t.end_span(), "truncated node block", hint))?;
                        tags.push(parse_usize(&t, &l[0], "a node tag")?);
                    }
                    for tag in tags {
                        let (_, l) = t
                            .next_line()
                            .ok_or_else(|| err(t.end_span(), "truncated node block", hint))?;
                        if l.len() < 3 {
                            return Err(err(
                                l[0].clone(),
                                "a node line has the coordinates x y z",
                                hint,
                            ));
                        }
                        let x = parse_f64(&t, &l[0], "x")?;
                        let y = parse_f64(&t, &l[1], "y")?;
                        node_index.insert(tag, coords.len());
                        coords.push([x, y]);
                    }
                }
                skip_to(&mut t, "$EndNodes")?;
            }
            "$Elements" => {
                let (_, n) = t
                    .next_line()
                    .ok_or_else(|| err(t.end_span(), "truncated $Elements", hint))?;
                let blocks = parse_usize(&t, &n[0], "the number of element blocks")?;
                for _ in 0..blocks {
                    let (_, b) = t
                        .next_line()
                        .ok_or_else(|| err(t.end_span(), "truncated $Elements", hint))?;
                    if b.len() < 4 {
                        return Err(err(
                            b[0].clone(),
                            "an element block header is `dim tag type count`",
                            hint,
                        ));
                    }
                    let dim = parse_usize(&t, &b[0], "the entity dimension")?;
                    let entity = parse_usize(&t, &b[1], "the entity tag")?;
                    let ty = parse_usize(&t, &b[2], "the element type")?;
                    let count = parse_usize(&t, &b[3], "the number of elements")?;
                    let nn = gmsh_nodes(ty).ok_or_else(|| {
                        err(
                            b[2].clone(),
                            format!("unknown Gmsh element type {ty}"),
                            hint,
                        )
                    })?;
                    let kind = if dim == 2 {
                        Some(gmsh_kind(ty).ok_or_else(|| {
                            err(b[2].clone(), format!("Gmsh element type {ty} is not a supported 2-D element"), Some("use 3- or 6-node triangles or 4-, 8- or 9-node quadrilaterals (Mesh.ElementOrder = 2, Mesh.SecondOrderIncomplete = 1 for 8-node quadrilaterals)"))
                        })?)
                    } else {
                        None
                    };
                    for _ in 0..count {
                        let (_, l) = t
                            .next_line()
                            .ok_or_else(|| err(t.end_span(), "truncated element block", hint))?;
                        if l.len() != nn + 1 {
                            return Err(err(
                                l[0].start..l.last().expect("token").end,
                                format!(
                                    "an element of type {ty} has {nn} nodes, this line lists {}",
                                    l.len() - 1
                                ),
                                hint,
                            ));
                        }
                        if let Some(kind) = kind {
                            let mut nodes = Vec::with_capacity(nn);
                            for r in &l[1..] {
                                nodes.push((parse_usize(&t, r, "a node tag")?, r.clone()));
                            }
                            raw_elements.push((
                                kind,
                                nodes,
                                entity,
                                l[0].start..l.last().expect("token").end,
                            ));
                        }
                    }
                }
                skip_to(&mut t, "$EndElements")?;
            }
            s if s.starts_with('$') && !s.starts_with("$End") => {
                let end = format!("$End{}", &s[1..]);
                skip_to(&mut t, &end)?;
            }
            _ => {
                return Err(err(
                    toks[0].clone(),
                    format!("unexpected '{head}' outside a section"),
                    hint,
                ));
            }
        }
    }
    if !seen_format {
        return Err(err(
            0..text.len().min(1),
            "not a Gmsh mesh: no $MeshFormat section",
            hint,
        ));
    }
    // Keep only the nodes of 2-D elements, renumbered.
    let mut out = MeshFile::default();
    let mut remap: HashMap<usize, usize> = HashMap::new();
    for (kind, nodes, entity, span) in raw_elements {
        let mut ns = [0; MAX_NODES];
        for (k, (tag, r)) in nodes.iter().enumerate() {
            let Some(&i) = node_index.get(tag) else {
                return Err(err(
                    r.clone(),
                    format!("node {tag} is not defined in $Nodes"),
                    None,
                ));
            };
            ns[k] = *remap.entry(i).or_insert_with(|| {
                out.nodes.push(coords[i]);
                out.nodes.len() - 1
            });
        }
        let region = match surface_physical.get(&entity).and_then(|p| p.first()) {
            Some(&tag) => physical_names
                .get(&(2, tag))
                .cloned()
                .unwrap_or_else(|| tag.to_string()),
            None => format!("surface {entity}"),
        };
        out.elements.push(FileElement {
            kind,
            nodes: ns,
            region,
            span,
        });
    }
    if out.elements.is_empty() {
        return Err(err(
            t.end_span(),
            "the Gmsh file has no 2-D elements",
            Some("mesh the section's surfaces (Mesh › 2D) and save physical groups for them"),
        ));
    }
    Ok(out)
}

fn skip_to(t: &mut Tokens, end: &str) -> Result<(), MeshFileError> {
    while let Some((_, toks)) = t.peek() {
        let w = t.word(&toks[0]);
        t.at += 1;
        if w == end {
            return Ok(());
        }
    }
    Err(err(t.end_span(), format!("missing {end}"), None))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_format_reads_and_locates_errors() {
        let text =
            "# a square\nnodes\n1 0 0\n2 1 0\n3 1 1\n4 0 1\nelements\n7 quad4 steel 1 2 3 4\n";
        let m = read_text(text).unwrap();
        assert_eq!(m.nodes.len(), 4);
        assert_eq!(m.elements[0].region, "steel");
        assert_eq!(&text[m.elements[0].span.clone()], "7 quad4 steel 1 2 3 4");
        let bad = text.replace("3 4\n", "3 9\n");
        let e = read_text(&bad).unwrap_err();
        assert_eq!(&bad[e.span.clone()], "9");
        assert!(e.message.contains("node 9"), "{}", e.message);
        let bad = text.replace("quad4", "quad5");
        let e = read_text(&bad).unwrap_err();
        assert_eq!(&bad[e.span.clone()], "quad5");
        let bad = text.replace("2 1 0", "2 1 x");
        let e = read_text(&bad).unwrap_err();
        assert_eq!(&bad[e.span.clone()], "x");
    }

    #[test]
    fn gmsh_v4_reads_physical_groups() {
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 5 \"core\"\n$EndPhysicalNames\n$Entities\n0 0 1 0\n1 0 0 0 1 1 0 1 5 0\n$EndEntities\n$Nodes\n1 4 1 4\n2 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 3 1\n1 1 2 3 4\n$EndElements\n";
        let m = read_gmsh(text).unwrap();
        assert_eq!(m.nodes.len(), 4);
        assert_eq!(m.elements.len(), 1);
        assert_eq!(m.elements[0].region, "core");
        assert_eq!(m.elements[0].kind, ElementKind::Quad4);
        let bad = text.replace("4.1 0 8", "2.2 0 8");
        assert!(
            read_gmsh(&bad)
                .unwrap_err()
                .message
                .contains("not supported")
        );
    }
}
