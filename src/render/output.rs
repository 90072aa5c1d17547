//! Where a [`super::Job`]'s pixels go, and the sink that writes them band by band.

use std::path::{Path, PathBuf};

use super::aov::{AovImage, ExrSource};
use crate::image::{Encoding, ExrStream, Format, Image, ImageError, PngStream};

/// Where a render's pixels go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Output {
    /// An 8-bit RGB PNG, written band by band as the rows come: memory stays one band,
    /// whatever the frame's size. Its bytes are encoded as the scene's
    /// [`crate::scene::Scene::encoding`] says; for a linear PNG the GPU packs the bytes
    /// itself (a quarter of the readback).
    Png(PathBuf),
    /// An OpenEXR file, the f32 image exactly with the hit distance t in alpha, written row
    /// by row as the rows come (uncompressed, [`crate::image::ExrStream`]): memory stays
    /// one band, whatever the frame's size.
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
    /// rows: for a file one band of f32 pixels and its encoding; in memory the whole frame.
    pub(crate) fn bytes_at_once(&self, w: u32, h: u32, band: u32) -> u64 {
        match self {
            Output::Png(_) => band as u64 * w as u64 * (16 + 3),
            Output::Exr(_) => band as u64 * w as u64 * 16 + (1 << 20),
            Output::Memory => w as u64 * h as u64 * 16,
        }
    }
}

/// An open output: a file being streamed, or the whole f32 image being filled.
pub(crate) enum Sink {
    /// The PNG's encoder.
    Png(Box<PngStream>),
    /// The EXR's writer.
    Exr(Box<ExrStream>),
    /// The frame, and how many of its pixels are written.
    Frame(Image, usize),
    /// An EXR of the colour and AOVs, written band by band as the CPU tracer makes them:
    /// the writer, and where each of its channels comes from.
    ExrAov(Box<ExrStream>, Vec<(String, bool, ExrSource)>),
}

impl Sink {
    /// Opens `output` for a `w`×`h` frame, a PNG's bytes encoded as `encoding` says.
    pub(crate) fn open(
        output: &Output,
        w: u32,
        h: u32,
        encoding: Encoding,
    ) -> Result<Sink, ImageError> {
        Ok(match output {
            Output::Png(path) => {
                Sink::Png(Box::new(PngStream::create_encoded(path, w, h, encoding)?))
            }
            Output::Exr(path) => Sink::Exr(Box::new(ExrStream::create(path, w, h)?)),
            Output::Memory => Sink::Frame(Image::new(w, h, [0.0; 4]), 0),
        })
    }

    /// Opens the EXR `path` for a `w`×`h` frame of colour and the AOVs `aovs` holds
    /// (a band of them: [`Sink::write_rows_aov`]).
    pub(crate) fn open_exr_aov(
        path: &Path,
        w: u32,
        h: u32,
        aovs: &AovImage,
    ) -> Result<Sink, ImageError> {
        let layout = aovs.exr_layout();
        let names: Vec<(&str, bool)> = layout.iter().map(|(n, u, _)| (n.as_str(), *u)).collect();
        let stream = ExrStream::create_channels(path, w, h, &names)?;
        Ok(Sink::ExrAov(Box::new(stream), layout))
    }

    /// Appends the next rows: `px`, f32 pixels, with the same rows of AOVs from the top of
    /// `band` (an [`Sink::ExrAov`]; another sink takes the colour alone).
    pub(crate) fn write_rows_aov(
        &mut self,
        px: &[[f32; 4]],
        band: &AovImage,
    ) -> Result<(), ImageError> {
        let Sink::ExrAov(e, layout) = self else {
            return self.write_rows(px);
        };
        let w = (band.width as usize).max(1);
        for (r, line) in px.chunks(w).enumerate() {
            e.write_row_with(|out| band.exr_row(layout, line, r, out))?;
        }
        Ok(())
    }

    /// Appends the next rows of f32 pixels.
    pub(crate) fn write_rows(&mut self, px: &[[f32; 4]]) -> Result<(), ImageError> {
        match self {
            Sink::Png(p) => p.write_rows(px),
            Sink::Exr(e) | Sink::ExrAov(e, _) => e.write_rows(px),
            Sink::Frame(img, at) => {
                img.pixels[*at..*at + px.len()].copy_from_slice(px);
                *at += px.len();
                Ok(())
            }
        }
    }

    /// Finishes the file (renamed over the output); the frame for [`Output::Memory`].
    pub(crate) fn finish(self) -> Result<Option<Image>, ImageError> {
        match self {
            Sink::Png(p) => p.finish().map(|_| None),
            Sink::Exr(e) | Sink::ExrAov(e, _) => e.finish().map(|_| None),
            Sink::Frame(img, _) => Ok(Some(img)),
        }
    }
}
