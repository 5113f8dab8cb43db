//! Reads eddy's VTK XML frames back for tests: the XML head through quick-xml, the appended
//! raw arrays (plain or zlib blocks, `header_type` UInt64) decoded here, written from the VTK
//! file-format description rather than from the writer. VTK's own readers check the same files
//! in `tests/vtk_readers.rs`.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use quick_xml::events::{BytesStart, Event};

/// One `<DataArray>` with its values as f64 (integers converted).
#[derive(Debug, Clone)]
pub struct Array {
    /// The element holding it: `Points`, `Verts`, `PointData`, `CellData` or `FieldData`.
    pub section: String,
    pub name: String,
    /// VTK's type name: `Float32`, `Float64`, `Int64`.
    pub kind: String,
    pub components: usize,
    pub values: Vec<f64>,
}

/// A VTK XML file: the attributes of its elements by element name (the first of each) and its
/// arrays in file order.
#[derive(Debug)]
pub struct VtkFile {
    pub elements: HashMap<String, HashMap<String, String>>,
    pub arrays: Vec<Array>,
}

impl VtkFile {
    /// The attribute `key` of element `element`.
    pub fn attr(&self, element: &str, key: &str) -> &str {
        self.elements
            .get(element)
            .and_then(|a| a.get(key))
            .unwrap_or_else(|| panic!("no {element}@{key}"))
    }

    /// The arrays of one section, in file order.
    pub fn section(&self, section: &str) -> Vec<&Array> {
        self.arrays
            .iter()
            .filter(|a| a.section == section)
            .collect()
    }
}

fn attributes(e: &BytesStart) -> HashMap<String, String> {
    e.attributes()
        .map(|a| {
            let a = a.expect("well-formed attribute");
            let key = String::from_utf8(a.key.as_ref().to_vec()).expect("UTF-8 key");
            let value = a.unescape_value().expect("escaped value").into_owned();
            (key, value)
        })
        .collect()
}

/// Reads `path` whole; panics with the reason on anything malformed.
pub fn read_vtk(path: &Path) -> VtkFile {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let marker = b"<AppendedData encoding=\"raw\">";
    let at = bytes
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("an appended raw section");
    let underscore = at + bytes[at..].iter().position(|&b| b == b'_').expect("'_'");
    let (head, appended) = (&bytes[..at], &bytes[underscore + 1..]);

    let mut reader = quick_xml::Reader::from_reader(head);
    let mut elements: HashMap<String, HashMap<String, String>> = HashMap::new();
    let mut stack: Vec<String> = Vec::new();
    let mut pending: Vec<(String, HashMap<String, String>, Option<String>)> = Vec::new();
    let mut buf = Vec::new();
    loop {
        let event = reader.read_event_into(&mut buf).expect("well-formed XML");
        match event {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                let attrs = attributes(e);
                if name == "DataArray" {
                    pending.push((stack.last().cloned().unwrap_or_default(), attrs, None));
                } else {
                    elements.entry(name.clone()).or_insert(attrs);
                }
                if matches!(event, Event::Start(_)) {
                    stack.push(name);
                }
            }
            Event::Text(t) if stack.last().map(String::as_str) == Some("DataArray") => {
                let text = t.unescape().expect("text").into_owned();
                pending.last_mut().expect("an open DataArray").2 = Some(text);
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    let file = &elements["VTKFile"];
    assert_eq!(file["header_type"], "UInt64");
    assert_eq!(file["byte_order"], "LittleEndian");
    let compressed = match file.get("compressor").map(String::as_str) {
        None => false,
        Some("vtkZLibDataCompressor") => true,
        Some(other) => panic!("unexpected compressor {other}"),
    };
    let arrays = pending
        .into_iter()
        .map(|(section, attrs, text)| {
            let kind = attrs["type"].clone();
            let values = match attrs["format"].as_str() {
                "ascii" => text
                    .expect("ascii values")
                    .split_whitespace()
                    .map(|v| v.parse().expect("a number"))
                    .collect(),
                "appended" => {
                    let offset: usize = attrs["offset"].parse().expect("offset");
                    let raw = decode(&appended[offset..], compressed);
                    numbers(&kind, &raw)
                }
                other => panic!("unexpected format {other}"),
            };
            Array {
                section,
                name: attrs["Name"].clone(),
                components: attrs
                    .get("NumberOfComponents")
                    .map_or(1, |c| c.parse().expect("components")),
                kind,
                values,
            }
        })
        .collect();
    VtkFile { elements, arrays }
}

fn u64_at(bytes: &[u8], k: usize) -> usize {
    u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap()) as usize
}

/// The bytes of one appended array starting at `data`.
fn decode(data: &[u8], compressed: bool) -> Vec<u8> {
    if !compressed {
        let n = u64_at(data, 0);
        return data[8..8 + n].to_vec();
    }
    let (blocks, block, last) = (u64_at(data, 0), u64_at(data, 1), u64_at(data, 2));
    let sizes: Vec<usize> = (0..blocks).map(|b| u64_at(data, 3 + b)).collect();
    let mut at = 8 * (3 + blocks);
    let mut out = Vec::new();
    for (b, size) in sizes.iter().enumerate() {
        let expected = if b + 1 == blocks && last > 0 {
            last
        } else {
            block
        };
        let mut chunk = Vec::new();
        flate2::read::ZlibDecoder::new(&data[at..at + size])
            .read_to_end(&mut chunk)
            .expect("a zlib block");
        assert_eq!(chunk.len(), expected, "block {b} size");
        out.extend(chunk);
        at += size;
    }
    out
}

fn numbers(kind: &str, raw: &[u8]) -> Vec<f64> {
    match kind {
        "Float32" => raw
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect(),
        "Float64" => raw
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect(),
        "Int64" => raw
            .chunks_exact(8)
            .map(|c| i64::from_le_bytes(c.try_into().unwrap()) as f64)
            .collect(),
        other => panic!("unexpected type {other}"),
    }
}
