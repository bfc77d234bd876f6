//! OpenEXR through the `exr` crate: one float channel read as a scalar map (depth files
//! from renderers), and 32-bit float RGBA images or one-channel `Y` maps written with
//! lossless compression so that outputs round-trip exactly.

use std::fs::File;
use std::io::{BufWriter, Cursor};
use std::path::Path;

use crate::raster::{Grid, RgbaImage, ScalarMap};
use crate::{Error, Result};

/// Reads a one-channel float map from an OpenEXR file: the first channel named `Z`, `Y`,
/// `R` or `depth` (in that order of preference), or the only channel.
pub fn read_exr_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_exr_scalar(&bytes, path)
}

pub(crate) fn parse_exr_scalar(bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    use exr::prelude::{read, FlatSamples, ReadChannels, ReadLayers};
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| Error::format(path, format!("cannot read as OpenEXR: {e}")))?;
    let layer = image.layer_data;
    let channels = &layer.channel_data.list;
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
    let (w, h) = (layer.size.width(), layer.size.height());
    let data: Vec<f32> = match &channels[chosen].sample_data {
        FlatSamples::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
        FlatSamples::F32(v) => v.clone(),
        FlatSamples::U32(v) => v.iter().map(|&x| x as f32).collect(),
    };
    if data.len() != w * h {
        return Err(Error::format(
            path,
            format!(
                "EXR channel {} is subsampled ({} samples for {w}x{h} pixels); expected full resolution",
                names[chosen],
                data.len()
            ),
        ));
    }
    Ok(Grid::from_vec(w, h, data))
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
