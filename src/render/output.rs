//! Where a [`super::Job`]'s pixels go, and the sink that writes them band by band.

use std::path::{Path, PathBuf};

use crate::image::{Format, Image, ImageError, PngStream};

/// Where a render's pixels go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// An 8-bit RGB PNG, written band by band as the rows come: memory stays one band,
    /// whatever the frame's size. The GPU packs the bytes itself (a quarter of the
    /// readback).
    Png(PathBuf),
    /// An OpenEXR file, the f32 image exactly with the hit distance t in alpha: the frame
    /// is held whole and written at the end.
    Exr(PathBuf),
    /// The f32 image in memory, handed back in [`super::RenderReport::image`].
    Memory,
}

impl Output {
    /// The file output that `path`'s extension names (`.png` or `.exr`), after checking,
    /// before any work, that the folder exists and a file can be made there.
    pub fn file(path: impl AsRef<Path>) -> Result<Output, ImageError> {
        let path = path.as_ref();
        crate::image::check_writable(path)?;
        Ok(match crate::image::format_of(path)? {
            Format::Png => Output::Png(path.to_owned()),
            Format::Exr => Output::Exr(path.to_owned()),
        })
    }

    /// The file, for the outputs that have one.
    pub fn path(&self) -> Option<&Path> {
        match self {
            Output::Png(p) | Output::Exr(p) => Some(p),
            Output::Memory => None,
        }
    }

    /// The bytes a `w`×`h` frame holds at once on the way to this output, bands of `band`
    /// rows: for a PNG one band of f32 pixels and its bytes; else the whole frame (and, for
    /// an EXR, the encoder's copy of it).
    pub(crate) fn bytes_at_once(&self, w: u32, h: u32, band: u32) -> u64 {
        let frame = w as u64 * h as u64 * 16;
        match self {
            Output::Png(_) => band as u64 * w as u64 * (16 + 3),
            Output::Exr(_) => frame * 2,
            Output::Memory => frame,
        }
    }
}

/// An open output: a PNG being streamed, or the whole f32 image being filled.
pub(crate) enum Sink {
    /// The PNG's encoder.
    Png(Box<PngStream>),
    /// The frame, and how many of its pixels are written.
    Frame(Image, usize),
}

impl Sink {
    /// Opens `output` for a `w`×`h` frame.
    pub(crate) fn open(output: &Output, w: u32, h: u32) -> Result<Sink, ImageError> {
        Ok(match output {
            Output::Png(path) => Sink::Png(Box::new(PngStream::create(path, w, h)?)),
            Output::Exr(_) | Output::Memory => Sink::Frame(Image::new(w, h, [0.0; 4]), 0),
        })
    }

    /// Appends the next rows of f32 pixels.
    pub(crate) fn write_rows(&mut self, px: &[[f32; 4]]) -> Result<(), ImageError> {
        match self {
            Sink::Png(p) => p.write_rows(px),
            Sink::Frame(img, at) => {
                img.pixels[*at..*at + px.len()].copy_from_slice(px);
                *at += px.len();
                Ok(())
            }
        }
    }

    /// Finishes the file (the PNG's last bytes, or the EXR written whole); the frame for
    /// [`Output::Memory`].
    pub(crate) fn finish(self, output: &Output) -> Result<Option<Image>, ImageError> {
        match (self, output) {
            (Sink::Png(p), _) => p.finish().map(|_| None),
            (Sink::Frame(img, _), Output::Exr(path)) => img.save_exr(path).map(|_| None),
            (Sink::Frame(img, _), _) => Ok(Some(img)),
        }
    }
}
