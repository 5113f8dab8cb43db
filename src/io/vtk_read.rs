//! Reading eddy's VTK XML frames back, for `eddy slice` on a run that wrote no HDF5: the grid
//! frames (ImageData, `.vti`), the particle frames (PolyData `.vtp`, or UnstructuredGrid `.vtu`)
//! and the `.pvd` series that lists them with their times.
//!
//! The XML head is parsed by quick-xml; the arrays are appended raw, plain or in zlib blocks
//! with 32- or 64-bit little-endian headers (the layout `super::vtk_xml` describes and writes),
//! and are decoded only when asked for. What eddy never writes (inline base64 arrays, big-endian
//! files, other compressors) is refused with the file's name rather than misread.

use std::io::Read;
use std::path::{Path, PathBuf};

use flate2::read::ZlibDecoder;
use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;

use super::IoError;
use crate::Real;

/// Where a VTK file's values lie.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Layout {
    /// A regular grid of `cells`, lowest corner `origin`, cell size `spacing` (ImageData); its
    /// values are cell data, x fastest.
    Image {
        origin: [Real; 3],
        spacing: [Real; 3],
        cells: [usize; 3],
    },
    /// This many points (PolyData, UnstructuredGrid); its values are point data.
    Points(usize),
}

impl Layout {
    /// The element that holds the values (`CellData` or `PointData`), and how many tuples.
    fn data(&self) -> (&'static str, usize) {
        match self {
            Layout::Image { cells, .. } => ("CellData", cells.iter().product()),
            Layout::Points(n) => ("PointData", *n),
        }
    }
}

/// A `<DataArray>` as the head declares it.
#[derive(Debug)]
struct ArrayTag {
    /// The element holding it: `Points`, `PointData`, `CellData`, `FieldData`, ...
    section: String,
    name: String,
    kind: String,
    components: usize,
    data: Data,
}

/// Where an array's values are.
#[derive(Debug)]
enum Data {
    /// At this byte offset into the appended section.
    Appended(usize),
    /// Inline as text (`format="ascii"`).
    Ascii(String),
    /// In a format this reader does not decode, named.
    Other(String),
}

/// An open VTK XML file: its head parsed, its appended section kept undecoded.
#[derive(Debug)]
pub(crate) struct VtkFile {
    pub(crate) path: PathBuf,
    pub(crate) layout: Layout,
    arrays: Vec<ArrayTag>,
    appended: Vec<u8>,
    /// Bytes of a size in the appended arrays' headers: 4 or 8.
    header: usize,
    compressed: bool,
}

/// The attributes of an element, unescaped; a malformed one is an error naming it.
fn attributes(e: &BytesStart) -> Result<Vec<(String, String)>, String> {
    e.attributes()
        .map(|a| {
            let a = a.map_err(|e| format!("malformed attribute: {e}"))?;
            let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
            let value = a
                .unescape_value()
                .map_err(|e| format!("attribute {key}: {e}"))?;
            Ok((key, value.into_owned()))
        })
        .collect()
}

/// The value of attribute `key`, or an error naming the element that lacks it.
fn attr<'a>(attrs: &'a [(String, String)], element: &str, key: &str) -> Result<&'a str, String> {
    attrs
        .iter()
        .find(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
        .ok_or_else(|| format!("<{element}> has no attribute {key}"))
}

/// The whitespace-separated numbers of `text`, exactly `N` of them.
fn numbers<T: std::str::FromStr, const N: usize>(text: &str, what: &str) -> Result<[T; N], String> {
    let values: Vec<T> = text
        .split_whitespace()
        .map(str::parse)
        .collect::<Result<_, _>>()
        .map_err(|_| format!("{what} {text:?} is not {N} numbers"))?;
    values
        .try_into()
        .map_err(|_| format!("{what} {text:?} is not {N} numbers"))
}

/// What the head says, element by element, gathered while it is parsed.
#[derive(Default)]
struct Head {
    file: Vec<(String, String)>,
    image: Option<Vec<(String, String)>>,
    points: Option<usize>,
    arrays: Vec<ArrayTag>,
}

impl Head {
    /// Takes in one opening tag, `parent` the element it is in.
    fn element(&mut self, e: &BytesStart, parent: Option<&str>) -> Result<(), String> {
        let attrs = attributes(e)?;
        match e.name().as_ref() {
            b"VTKFile" => self.file = attrs,
            b"ImageData" => self.image = Some(attrs),
            b"Piece" if self.image.is_none() => {
                let n = attr(&attrs, "Piece", "NumberOfPoints")?;
                let n: usize = n
                    .parse()
                    .map_err(|_| format!("NumberOfPoints {n:?} is not a count"))?;
                // Each piece adds its points; eddy writes one.
                self.points = Some(self.points.unwrap_or(0).saturating_add(n));
            }
            b"DataArray" => self.arrays.push(array_tag(&attrs, parent)?),
            _ => {}
        }
        Ok(())
    }
}

/// The tag of a `<DataArray>` with attributes `attrs`, inside element `parent`.
fn array_tag(attrs: &[(String, String)], parent: Option<&str>) -> Result<ArrayTag, String> {
    let get = |key| attr(attrs, "DataArray", key);
    let name = get("Name").unwrap_or("").to_owned();
    let components = match get("NumberOfComponents") {
        Ok(c) => c
            .parse()
            .ok()
            .filter(|&c: &usize| c > 0)
            .ok_or_else(|| format!("array {name:?}: NumberOfComponents {c:?}"))?,
        Err(_) => 1,
    };
    let data = match get("format")? {
        "appended" => {
            let offset = get("offset")?;
            Data::Appended(
                offset
                    .parse()
                    .map_err(|_| format!("array {name:?}: offset {offset:?}"))?,
            )
        }
        "ascii" => Data::Ascii(String::new()),
        other => Data::Other(other.to_owned()),
    };
    Ok(ArrayTag {
        section: parent.unwrap_or("").to_owned(),
        name,
        kind: get("type")?.to_owned(),
        components,
        data,
    })
}

/// Parses the XML head `head` (the file up to its appended section).
fn parse_head(head: &[u8]) -> Result<Head, String> {
    let mut reader = Reader::from_reader(head);
    let mut parsed = Head::default();
    let mut stack: Vec<String> = Vec::new();
    let mut buf = Vec::new();
    loop {
        let event = reader
            .read_event_into(&mut buf)
            .map_err(|e| format!("malformed XML at byte {}: {e}", reader.buffer_position()))?;
        match &event {
            Event::Start(e) | Event::Empty(e) => {
                parsed.element(e, stack.last().map(String::as_str))?;
                if matches!(event, Event::Start(_)) {
                    stack.push(String::from_utf8_lossy(e.name().as_ref()).into_owned());
                }
            }
            Event::Text(t) if stack.last().is_some_and(|s| s == "DataArray") => {
                let text = t.unescape().map_err(|e| format!("array text: {e}"))?;
                if let Some(ArrayTag {
                    data: Data::Ascii(s),
                    ..
                }) = parsed.arrays.last_mut()
                {
                    s.push_str(&text);
                }
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    Ok(parsed)
}

/// The grid of an `<ImageData>` with attributes `attrs`: its cells span the extent's points.
fn image_layout(attrs: &[(String, String)]) -> Result<Layout, String> {
    let get = |key| attr(attrs, "ImageData", key);
    let extent: [i64; 6] = numbers(get("WholeExtent")?, "WholeExtent")?;
    let origin: [Real; 3] = numbers(get("Origin")?, "Origin")?;
    let spacing: [Real; 3] = numbers(get("Spacing")?, "Spacing")?;
    let cells = [0, 1, 2].map(|a| {
        let n = extent[2 * a + 1].checked_sub(extent[2 * a])?;
        usize::try_from(n).ok()
    });
    let (Some(nx), Some(ny), Some(nz)) = (cells[0], cells[1], cells[2]) else {
        return Err(format!("WholeExtent {extent:?} runs backwards"));
    };
    if nx.checked_mul(ny).and_then(|n| n.checked_mul(nz)).is_none() {
        return Err(format!(
            "WholeExtent {extent:?} holds more cells than memory"
        ));
    }
    if spacing.iter().any(|h| !(h.is_finite() && *h > 0.0)) || origin.iter().any(|o| !o.is_finite())
    {
        return Err(format!(
            "Origin {origin:?} or Spacing {spacing:?} is not finite and positive"
        ));
    }
    Ok(Layout::Image {
        origin: [0, 1, 2].map(|a| origin[a] + extent[2 * a] as Real * spacing[a]),
        spacing,
        cells: [nx, ny, nz],
    })
}

impl VtkFile {
    /// Reads `path` and parses its head; the arrays are decoded when read.
    pub(crate) fn open(path: &Path) -> Result<Self, IoError> {
        let bytes = std::fs::read(path).map_err(|e| IoError::io(path, "reading", e))?;
        Self::parse(path, bytes)
            .map_err(|why| IoError::invalid(path, format!("not a VTK frame eddy reads: {why}")))
    }

    fn parse(path: &Path, mut bytes: Vec<u8>) -> Result<Self, String> {
        let appended = split_appended(&mut bytes)?;
        let head = parse_head(&bytes)?;
        let file = |key| attr(&head.file, "VTKFile", key);
        if file("byte_order").unwrap_or("LittleEndian") != "LittleEndian" {
            return Err("big-endian data is not read".into());
        }
        let header = match file("header_type").unwrap_or("UInt32") {
            "UInt32" => 4,
            "UInt64" => 8,
            other => return Err(format!("header_type {other} is neither UInt32 nor UInt64")),
        };
        let compressed = match file("compressor") {
            Err(_) => false,
            Ok("vtkZLibDataCompressor") => true,
            Ok(other) => return Err(format!("compressor {other} is not read (only zlib)")),
        };
        let layout = match (file("type")?, &head.image, head.points) {
            ("ImageData", Some(image), _) => image_layout(image)?,
            ("PolyData" | "UnstructuredGrid", _, Some(n)) => Layout::Points(n),
            (other, ..) => {
                return Err(format!(
                    "a {other} file: frames are ImageData (.vti) or PolyData (.vtp)"
                ))
            }
        };
        Ok(VtkFile {
            path: path.to_path_buf(),
            layout,
            arrays: head.arrays,
            appended,
            header,
            compressed,
        })
    }

    /// The frame's time: its `TimeValue` field, as eddy and ParaView store it.
    pub(crate) fn time(&self) -> Option<Real> {
        let tag = self.find("FieldData", "TimeValue")?;
        self.values(tag).ok()?.first().copied()
    }

    /// The fields of the values' element (cell data of a grid, point data of points) with
    /// their components per tuple, in file order.
    pub(crate) fn fields(&self) -> Vec<(&str, usize)> {
        let (section, _) = self.layout.data();
        self.arrays
            .iter()
            .filter(|a| a.section == section)
            .map(|a| (a.name.as_str(), a.components))
            .collect()
    }

    /// The values of field `name` (see [`Self::fields`]), tuples in file order with their
    /// components side by side.
    pub(crate) fn field(&self, name: &str) -> Result<Vec<Real>, IoError> {
        let (section, tuples) = self.layout.data();
        self.read(section, name, tuples)
    }

    /// The points' coordinates, x, y, z side by side.
    pub(crate) fn points(&self) -> Result<Vec<Real>, IoError> {
        let (_, tuples) = self.layout.data();
        self.read("Points", "", tuples)
    }

    fn find(&self, section: &str, name: &str) -> Option<&ArrayTag> {
        // The points' array may have any name: there is one.
        self.arrays
            .iter()
            .find(|a| a.section == section && (section == "Points" || a.name == name))
    }

    /// The values of an array, checked to hold `tuples` tuples.
    fn read(&self, section: &str, name: &str, tuples: usize) -> Result<Vec<Real>, IoError> {
        let what = if section == "Points" {
            "the points".to_owned()
        } else {
            format!("array `{name}`")
        };
        let fail = |why: String| IoError::invalid(&self.path, format!("{what}: {why}"));
        let tag = self
            .find(section, name)
            .ok_or_else(|| fail(format!("no such array in <{section}>")))?;
        let values = self.values(tag).map_err(fail)?;
        let expected = tuples.saturating_mul(tag.components);
        if values.len() != expected {
            return Err(fail(format!(
                "{} values, expected {expected} ({tuples} x {})",
                values.len(),
                tag.components
            )));
        }
        Ok(values)
    }

    fn values(&self, tag: &ArrayTag) -> Result<Vec<Real>, String> {
        match &tag.data {
            Data::Ascii(text) => text
                .split_whitespace()
                .map(|v| v.parse().map_err(|_| format!("{v:?} is not a number")))
                .collect(),
            Data::Appended(offset) => decode_numbers(&tag.kind, &self.raw(*offset)?),
            Data::Other(format) => Err(format!(
                "format=\"{format}\" is not read (eddy appends raw data)"
            )),
        }
    }

    /// A size field of the appended arrays' headers at byte `at` of `data`.
    fn size(&self, data: &[u8], at: usize) -> Result<usize, String> {
        let field = at
            .checked_add(self.header)
            .and_then(|end| data.get(at..end))
            .ok_or("the appended data ends inside an array's header")?;
        let mut bytes = [0u8; 8];
        bytes[..self.header].copy_from_slice(field);
        usize::try_from(u64::from_le_bytes(bytes)).map_err(|_| "a size past memory".to_owned())
    }

    /// The bytes of the appended array at `offset`: plain, or its zlib blocks inflated.
    fn raw(&self, offset: usize) -> Result<Vec<u8>, String> {
        let data = self
            .appended
            .get(offset..)
            .ok_or_else(|| format!("offset {offset} lies past the appended data"))?;
        let h = self.header;
        let short = || "the appended data ends inside an array".to_owned();
        if !self.compressed {
            let n = self.size(data, 0)?;
            let end = h.checked_add(n).ok_or_else(short)?;
            return data.get(h..end).map(<[u8]>::to_vec).ok_or_else(short);
        }
        let (blocks, block, last) = (
            self.size(data, 0)?,
            self.size(data, h)?,
            self.size(data, 2 * h)?,
        );
        if blocks > data.len() / h {
            return Err(short());
        }
        let mut at = h * (3 + blocks);
        let mut out = Vec::new();
        for b in 0..blocks {
            let size = self.size(data, h * (3 + b))?;
            let expected = if b + 1 == blocks && last > 0 {
                last
            } else {
                block
            };
            let end = at.checked_add(size).ok_or_else(short)?;
            let zipped = data.get(at..end).ok_or_else(short)?;
            let before = out.len();
            // At most one byte more than the block holds, so a corrupt block cannot grow
            // without bound.
            ZlibDecoder::new(zipped)
                .take(expected as u64 + 1)
                .read_to_end(&mut out)
                .map_err(|e| format!("zlib block {b}: {e}"))?;
            if out.len() - before != expected {
                return Err(format!(
                    "zlib block {b} inflates to {} bytes, its header says {expected}",
                    out.len() - before
                ));
            }
            at = end;
        }
        Ok(out)
    }
}

/// Cuts the appended section off `bytes`, leaving the XML head, and returns its raw bytes:
/// those after `<AppendedData encoding="raw">` and an underscore (none without the section).
fn split_appended(bytes: &mut Vec<u8>) -> Result<Vec<u8>, String> {
    let marker = b"<AppendedData";
    let Some(at) = bytes.windows(marker.len()).position(|w| w == marker) else {
        return Ok(Vec::new());
    };
    let close = bytes[at..]
        .iter()
        .position(|&b| b == b'>')
        .map(|c| at + c)
        .ok_or("<AppendedData> is not closed")?;
    let tag = String::from_utf8_lossy(&bytes[at..close]).into_owned();
    if !tag.contains("encoding=\"raw\"") {
        return Err(format!("{tag}>: only raw appended data is read"));
    }
    let underscore = bytes[close..]
        .iter()
        .position(|&b| b == b'_')
        .map(|u| close + u)
        .ok_or("<AppendedData> has no `_` before its data")?;
    let data = bytes.split_off(underscore + 1);
    bytes.truncate(at);
    Ok(data)
}

/// Little-endian numbers of VTK type `kind` in `raw`, as reals.
fn decode_numbers(kind: &str, raw: &[u8]) -> Result<Vec<Real>, String> {
    fn each<const N: usize>(raw: &[u8], f: fn([u8; N]) -> Real) -> Result<Vec<Real>, String> {
        if !raw.len().is_multiple_of(N) {
            return Err(format!("{} bytes are no whole number of values", raw.len()));
        }
        Ok(raw
            .chunks_exact(N)
            .map(|c| {
                let mut b = [0u8; N];
                b.copy_from_slice(c);
                f(b)
            })
            .collect())
    }
    match kind {
        "Float32" => each(raw, |b| f32::from_le_bytes(b) as Real),
        "Float64" => each(raw, f64::from_le_bytes),
        "Int32" => each(raw, |b| i32::from_le_bytes(b) as Real),
        "Int64" => each(raw, |b| i64::from_le_bytes(b) as Real),
        other => Err(format!("type {other} is not read")),
    }
}

/// The frames a `.pvd` series lists: each `<DataSet>`'s time and file (resolved against the
/// series' folder), in the order listed.
pub(crate) fn read_pvd(path: &Path) -> Result<Vec<(Real, PathBuf)>, IoError> {
    let text = std::fs::read(path).map_err(|e| IoError::io(path, "reading", e))?;
    let fail = |why: String| IoError::invalid(path, format!("not a ParaView series: {why}"));
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut reader = Reader::from_reader(text.as_slice());
    let mut frames = Vec::new();
    let mut buf = Vec::new();
    loop {
        match reader.read_event_into(&mut buf) {
            Ok(Event::Start(e) | Event::Empty(e)) if e.name().as_ref() == b"DataSet" => {
                let attrs = attributes(&e).map_err(&fail)?;
                let time = attr(&attrs, "DataSet", "timestep").map_err(&fail)?;
                let time: Real = time
                    .parse()
                    .map_err(|_| fail(format!("timestep {time:?} is not a number")))?;
                let file = attr(&attrs, "DataSet", "file").map_err(&fail)?;
                frames.push((time, folder.join(file)));
            }
            Ok(Event::Eof) => break,
            Ok(_) => {}
            Err(e) => return Err(fail(format!("malformed XML: {e}"))),
        }
        buf.clear();
    }
    Ok(frames)
}
