//! OpenEXR through the `exr` crate: one float channel read as a scalar map (depth files
//! from renderers; the header is checked against `io::limits` before any pixel is
//! decoded), and 32-bit float RGBA images or one-channel `Y` maps written with lossless
//! compression so that outputs round-trip exactly.

use std::fs::File;
use std::io::{BufWriter, Cursor};
use std::path::Path;

use crate::io::limits::check_size;
use crate::raster::{Grid, RgbaImage, ScalarMap};
use crate::{Error, Result};

/// Reads a one-channel float map from an OpenEXR file: the first channel named `Z`, `Y`,
/// `R` or `depth` (in that order of preference), or the only channel.
pub fn read_exr_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_exr_scalar(&bytes, path)
}

pub(crate) fn parse_exr_scalar(bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    use exr::prelude::{read, ReadChannels, ReadLayers, ReadSpecificChannel};
    let bad = |e: exr::error::Error| Error::format(path, format!("cannot read as OpenEXR: {e}"));
    // The decoder allocates for the size its header claims before reading any pixel, so
    // the header is read and checked on its own first.
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(bad)?;
    for header in meta.headers.iter() {
        check_header(header, bytes.len(), path)?;
    }
    // Like the decoder's `first_valid_layer` when every channel is read: the first layer.
    let header = meta
        .headers
        .first()
        .ok_or_else(|| Error::format(path, "EXR file has no layer; expected one"))?;
    let channels = &header.channels.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    let chosen = ["Z", "Y", "R", "depth"]
        .iter()
        .find_map(|want| names.iter().position(|n| n == want))
        .or(if names.len() == 1 { Some(0) } else { None })
        .ok_or_else(|| {
            Error::format(
                path,
                format!(
                    "EXR channels are [{}]; expected one named Z, Y, R or depth, or a single channel",
                    names.join(", ")
                ),
            )
        })?;
    let (w, h) = (header.layer_size.width(), header.layer_size.height());
    let sampling = channels[chosen].sampling;
    if (sampling.x(), sampling.y()) != (1, 1) {
        return Err(Error::format(
            path,
            format!(
                "EXR channel {} is subsampled ({}x{} pixels per sample for {w}x{h} pixels); expected full resolution",
                names[chosen],
                sampling.x(),
                sampling.y()
            ),
        ));
    }
    // Only the chosen channel is decoded: the others could hold many times its size.
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required(names[chosen].as_str())
        .collect_pixels(
            |size, _| vec![f32::NAN; size.area()],
            move |data: &mut Vec<f32>, pos, (v,): (f32,)| data[pos.y() * w + pos.x()] = v,
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(bad)?;
    let layer = image.layer_data;
    let size = layer.size;
    if (size.width(), size.height()) != (w, h) {
        return Err(Error::format(
            path,
            format!(
                "EXR layer read is {}x{} but its header says {w}x{h}",
                size.width(),
                size.height()
            ),
        ));
    }
    Ok(Grid::from_vec(w, h, layer.channel_data.pixels))
}

/// Refuses a layer whose claimed size is beyond `io::limits`, or which the file is too
/// short to hold: every chunk takes an 8-byte offset and an 8-byte chunk header at least,
/// and uncompressed pixels take their full size.
fn check_header(header: &exr::meta::header::Header, file_len: usize, path: &Path) -> Result<()> {
    let size = header.layer_size;
    check_size(path, "EXR", size.width() as u64, size.height() as u64)?;
    let chunks = header.chunk_count as u64;
    let mut needed = chunks.saturating_mul(16);
    if header.compression == exr::compression::Compression::Uncompressed {
        let pixels = (size.width() * size.height()) as u64;
        needed =
            needed.saturating_add(pixels.saturating_mul(header.channels.bytes_per_pixel as u64));
    }
    if needed > file_len as u64 {
        return Err(Error::format(
            path,
            format!(
                "EXR header claims {}x{} pixels in {chunks} chunks ({:?}), which need at least \
                 {needed} bytes, but the file has {file_len}; it is truncated or corrupt",
                size.width(),
                size.height(),
                header.compression
            ),
        ));
    }
    Ok(())
}

/// Writes an RGBA image as four 32-bit channels `R`, `G`, `B`, `A`.
pub(crate) fn write_rgba(out: &mut BufWriter<&File>, img: &RgbaImage) -> std::io::Result<()> {
    let channel = |c: usize| img.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
    let channels = [
        ("R", channel(0)),
        ("G", channel(1)),
        ("B", channel(2)),
        ("A", channel(3)),
    ];
    write_exr(out, img.width(), img.height(), channels)
}

/// Writes a scalar map as one 32-bit channel named `Y`, which [`read_exr_scalar`] reads
/// back.
pub(crate) fn write_scalar(out: &mut BufWriter<&File>, map: &ScalarMap) -> std::io::Result<()> {
    let channels = [("Y", map.as_slice().to_vec())];
    write_exr(out, map.width(), map.height(), channels)
}

fn write_exr<const N: usize>(
    out: &mut BufWriter<&File>,
    width: usize,
    height: usize,
    channels: [(&str, Vec<f32>); N],
) -> std::io::Result<()> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
        WritableImage,
    };
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(name, data)| AnyChannel::new(name, FlatSamples::F32(data)))
        .collect();
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer)
        .write()
        .to_buffered(out)
        .map_err(|e| std::io::Error::other(format!("OpenEXR encoder: {e}")))
}
