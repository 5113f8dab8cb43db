//! The animated GIF of `eddy slice`: its frames drawn as the PNGs are (by the figure drawing
//! all eddy figures use, with its bundled font), into memory, and encoded by the `gif` crate in
//! one palette fixed for the whole animation, so a value has the same colour in every frame.
//! Written under a temporary name and renamed when complete.

use std::collections::HashMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use gif::{Encoder, Repeat};
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use crate::io::atomic::temp_sibling;
use crate::io::plot::{draw_pixels, Figure};
use crate::io::IoError;
use crate::Real;

/// Time between frames, in the GIF's hundredths of a second: 10 frames a second.
const DELAY: u16 = 10;
/// Steps of the colour map in the palette, the rest being greys and the outline's colour.
const MAP_STEPS: usize = 200;
const GREYS: usize = 55;

/// An animated GIF being written.
pub(super) struct Animation {
    out: PathBuf,
    /// The GIF's temporary name.
    tmp: PathBuf,
    encoder: Option<Encoder<BufWriter<File>>>,
    size: (u32, u32),
    palette: Vec<[u8; 3]>,
    /// The palette index of each colour met so far.
    index: HashMap<[u8; 3], u8>,
}

/// The palette of every frame: steps of the viridis map (the cells and dots), greys from
/// black to white (background, text and its anti-aliasing, values that are not finite) and
/// `outline`.
fn palette(outline: RGBColor) -> Vec<[u8; 3]> {
    let map = (0..MAP_STEPS).map(|k| {
        let c = ViridisRGB::get_color(k as Real / (MAP_STEPS - 1) as Real);
        [c.0, c.1, c.2]
    });
    let greys = (0..GREYS).map(|k| [(255 * k / (GREYS - 1)) as u8; 3]);
    map.chain(greys)
        .chain([[outline.0, outline.1, outline.2]])
        .collect()
}

impl Animation {
    /// Starts `out`, of frames of `size` pixels, looping forever.
    pub(super) fn create(out: &Path, size: (u32, u32), outline: RGBColor) -> Result<Self, IoError> {
        let tmp = temp_sibling(out)?;
        let (Ok(w), Ok(h)) = (u16::try_from(size.0), u16::try_from(size.1)) else {
            return Err(IoError::invalid(
                out,
                format!("a GIF is at most 65535 pixels a side, the figure is {size:?}"),
            ));
        };
        let palette = palette(outline);
        let flat: Vec<u8> = palette.iter().flatten().copied().collect();
        let file = File::create(&tmp).map_err(|e| IoError::io(&tmp, "creating", e))?;
        let mut animation = Animation {
            out: out.to_path_buf(),
            tmp,
            encoder: None,
            size,
            palette,
            index: HashMap::new(),
        };
        let encoder = Encoder::new(BufWriter::new(file), w, h, &flat)
            .and_then(|mut e| e.set_repeat(Repeat::Infinite).map(|()| e))
            .map_err(|e| animation.fail(e))?;
        animation.encoder = Some(encoder);
        Ok(animation)
    }

    fn fail(&self, e: impl std::fmt::Display) -> IoError {
        IoError::invalid(&self.out, format!("writing the GIF: {e}"))
    }

    /// Draws `figure` as the next frame and returns what it returns.
    pub(super) fn push<F: Figure>(&mut self, figure: F) -> Result<F::Output, IoError> {
        let (pixels, output) = draw_pixels(&self.out, self.size, figure)?;
        let frame = gif::Frame {
            width: self.size.0 as u16,
            height: self.size.1 as u16,
            delay: DELAY,
            buffer: self.indices(&pixels).into(),
            ..gif::Frame::default()
        };
        let written = match self.encoder.as_mut() {
            Some(encoder) => encoder.write_frame(&frame).map_err(|e| e.to_string()),
            None => Err("closed".to_owned()),
        };
        written.map_err(|e| self.fail(e))?;
        Ok(output)
    }

    /// The palette index of each pixel (RGB bytes): the nearest colour of the palette.
    fn indices(&mut self, pixels: &[u8]) -> Vec<u8> {
        let palette = &self.palette;
        pixels
            .chunks_exact(3)
            .map(|p| {
                let c = [p[0], p[1], p[2]];
                *self.index.entry(c).or_insert_with(|| nearest(palette, c))
            })
            .collect()
    }

    /// Ends the GIF and renames it to its name.
    pub(super) fn finish(mut self) -> Result<(), IoError> {
        let encoder = self.encoder.take().ok_or_else(|| self.fail("closed"))?;
        let file = encoder
            .into_inner()
            .map_err(|e| self.fail(e))?
            .into_inner()
            .map_err(|e| IoError::io(&self.tmp, "writing", e.into_error()))?;
        file.sync_all()
            .map_err(|e| IoError::io(&self.tmp, "syncing", e))?;
        std::fs::rename(&self.tmp, &self.out)
            .map_err(|e| IoError::io(&self.out, "renaming the finished GIF to", e))
    }
}

/// Removes the GIF's temporary file unless it was renamed.
impl Drop for Animation {
    fn drop(&mut self) {
        drop(self.encoder.take());
        let _ = std::fs::remove_file(&self.tmp);
    }
}

/// The index of the colour of `palette` nearest `c`.
fn nearest(palette: &[[u8; 3]], c: [u8; 3]) -> u8 {
    let distance = |p: &[u8; 3]| {
        p.iter()
            .zip(&c)
            .map(|(a, b)| (i32::from(*a) - i32::from(*b)).pow(2))
            .sum::<i32>()
    };
    let best = (0..palette.len()).min_by_key(|&k| distance(&palette[k]));
    best.unwrap_or(0) as u8
}
