//! OpenEXR through the `exr` crate: a scalar map (depth) or a colour image read from the
//! channels renderers and engines name them, in any part of a multi-part file, with every
//! header checked against `io::limits` and [`MAX_EXR_BLOCK_BYTES`] (and every DWA block's
//! claimed sizes against its pixels) before any pixel is decoded, and the blocks decoded on
//! brume's pool, where a decoder panic is an error; and 32-bit float RGBA images or
//! one-channel `Y` maps written with lossless compression so that outputs round-trip
//! exactly.
//!
//! Channel names: OpenEXR has no layer field, so tools put the layer in the name, joined by
//! dots: `R` is a flat channel, `depth.Z` (Nuke) the `Z` of layer `depth`, and
//! `ViewLayer.Depth.Z` or `ViewLayer.Combined.R` (Blender multilayer) a pass of a view
//! layer. Here a channel's *layer* is everything before its last dot, and in a multi-part
//! file the part's name is put in front, as if the channel were named `part.channel`.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Cursor};
use std::panic::AssertUnwindSafe;
use std::path::Path;

use exr::meta::attribute::{ChannelList, Text};
use exr::meta::header::Header;
use rayon::iter::{ParallelBridge, ParallelIterator};

use crate::io::limits::check_size;
use crate::raster::{Grid, RgbImage, RgbaImage, ScalarMap};
use crate::{Error, Result};

/// Reads a one-channel float map from an OpenEXR file; the channel is chosen by
/// [`DEPTH_CHANNEL_ORDER`].
pub fn read_exr_scalar(path: &Path) -> Result<ScalarMap> {
    let bytes = crate::io::limits::read_file(path)?;
    parse_exr_scalar(&bytes, path)
}

/// The order in which a depth (or any scalar) map's channel is chosen, first match wins;
/// within one rule, the first channel in the file (channels are sorted by name, parts come
/// in file order).
///
/// 1. `Z`, a flat channel.
/// 2. `Z` of a layer with `Depth` (any case) in its path: `depth.Z` (Nuke), `Depth.Z`,
///    `ViewLayer.Depth.Z` (Blender).
/// 3. `Z` of any other layer, `<layer>.Z`.
/// 4. `depth` or `Depth`, a flat channel.
/// 5. `Y`, a flat channel (what brume writes for a scalar map).
/// 6. `R`, a flat channel (a grey map stored in red).
/// 7. The only channel of the file.
///
/// A `Z` (or flat `Y`) is never taken from a layer that also has an `X` channel (a
/// vector: normals, positions, motion), nor a `Z` from a layer with `Mist` in its path
/// (Blender stores its mist pass as a `Z` channel too, but it holds a 0-1 fog factor, not
/// a distance). `depth` comes before `Y` and `R` so that a file holding colour and a
/// `depth` channel gives its depth, not its red.
pub const DEPTH_CHANNEL_ORDER: &str = "Z; <layer>.Z with Depth in the layer's name \
     (depth.Z, ViewLayer.Depth.Z); any other <layer>.Z except vectors (beside an X) and Mist; \
     depth or Depth; Y; R; the only channel";

/// A channel of a flat (not deep) part of a file, as the choice rules see it.
struct Channel<'m> {
    /// Index of the part holding it.
    part: usize,
    /// That part's header.
    header: &'m Header,
    /// Its name inside the part, as stored.
    text: &'m Text,
    /// Its name with the part's in front in a multi-part file (`part.name`).
    full: String,
}

impl Channel<'_> {
    /// Everything before the last dot: `ViewLayer.Depth` for `ViewLayer.Depth.Z`, empty
    /// for a flat channel.
    fn layer(&self) -> &str {
        self.full.rsplit_once('.').map_or("", |(layer, _)| layer)
    }

    /// The name after the last dot: `Z` for `ViewLayer.Depth.Z`.
    fn leaf(&self) -> &str {
        self.full
            .rsplit_once('.')
            .map_or(&self.full, |(_, leaf)| leaf)
    }

    /// Whether a component of the layer's path is `name` (case ignored).
    fn layer_has(&self, name: &str) -> bool {
        self.layer()
            .split('.')
            .any(|part| part.eq_ignore_ascii_case(name))
    }
}

/// Every channel of a file's flat parts (parts in file order, channels in the order of
/// each part's list: sorted by name, as the format requires), indexed by part, layer and
/// name so that finding a channel's siblings stays linear in a header listing thousands.
struct Channels<'m> {
    all: Vec<Channel<'m>>,
    index: HashMap<(usize, String, String), usize>,
}

impl<'m> Channels<'m> {
    fn new(meta: &'m exr::meta::MetaData) -> Self {
        let multi_part = meta.headers.len() > 1;
        let all: Vec<Channel> = meta
            .headers
            .iter()
            .enumerate()
            .filter(|(_, h)| !h.deep)
            .flat_map(|(part, header)| {
                let name = header
                    .own_attributes
                    .layer_name
                    .as_ref()
                    .filter(|_| multi_part);
                header.channels.list.iter().map(move |c| Channel {
                    part,
                    header,
                    text: &c.name,
                    full: match name {
                        Some(name) => format!("{name}.{}", c.name),
                        None => c.name.to_string(),
                    },
                })
            })
            .collect();
        let mut index = HashMap::with_capacity(all.len());
        for (i, c) in all.iter().enumerate() {
            // A malformed file may repeat a name: the rules see its first channel.
            index
                .entry((c.part, c.layer().to_string(), c.leaf().to_string()))
                .or_insert(i);
        }
        Channels { all, index }
    }

    /// The channel named `leaf` in `c`'s layer and part.
    fn sibling(&self, c: &Channel, leaf: &str) -> Option<&Channel<'m>> {
        let key = (c.part, c.layer().to_string(), leaf.to_string());
        self.index.get(&key).map(|&i| &self.all[i])
    }

    /// The first channel that `rule` accepts.
    fn first(&self, rule: impl Fn(&Channel) -> bool) -> Option<&Channel<'m>> {
        self.all.iter().find(|c| rule(c))
    }

    /// The channel [`DEPTH_CHANNEL_ORDER`] picks, if any.
    fn depth(&self) -> Option<&Channel<'m>> {
        let z =
            |c: &Channel| c.leaf() == "Z" && !c.layer_has("Mist") && self.sibling(c, "X").is_none();
        let flat = |c: &Channel, names: &[&str]| names.contains(&c.full.as_str());
        let rules: [&dyn Fn(&Channel) -> bool; 6] = [
            &|c| z(c) && c.layer().is_empty(),
            &|c| z(c) && c.layer_has("depth"),
            &|c| z(c),
            &|c| flat(c, &["depth", "Depth"]),
            &|c| flat(c, &["Y"]) && self.sibling(c, "X").is_none(),
            &|c| flat(c, &["R"]),
        ];
        rules
            .iter()
            .find_map(|rule| self.first(rule))
            .or(if self.all.len() == 1 {
                self.all.first()
            } else {
                None
            })
    }

    /// The `R`, `G` and `B` of one layer: flat first, then the first layer with
    /// `Combined` in its path, then the first layer that has all three.
    fn rgb(&self) -> Option<[&Channel<'m>; 3]> {
        let triple = |r: &Channel| -> Option<[&Channel<'m>; 3]> {
            if r.leaf() != "R" {
                return None;
            }
            let r = self.sibling(r, "R")?;
            Some([r, self.sibling(r, "G")?, self.sibling(r, "B")?])
        };
        let rules: [&dyn Fn(&Channel) -> bool; 3] = [
            &|c| c.layer().is_empty(),
            &|c| c.layer_has("Combined"),
            &|_| true,
        ];
        rules
            .iter()
            .find_map(|rule| self.all.iter().filter(|c| rule(c)).find_map(triple))
    }

    /// The names for a message, the first few only: a hostile header can list thousands.
    fn list(&self) -> String {
        const SHOWN: usize = 12;
        let mut names: Vec<&str> = self
            .all
            .iter()
            .take(SHOWN)
            .map(|c| c.full.as_str())
            .collect();
        let more = format!("… {} more", self.all.len().saturating_sub(SHOWN));
        if self.all.len() > SHOWN {
            names.push(&more);
        }
        format!("[{}]", names.join(", "))
    }
}

/// Reads the headers and checks every part against `io::limits` and the file's length,
/// and every DWA block's claims ([`check_dwa_blocks`]). The decoder allocates for the
/// size its header claims before reading any pixel, so the header is read and checked on
/// its own first.
fn checked_meta(bytes: &[u8], path: &Path) -> Result<exr::meta::MetaData> {
    let meta = checked_headers(bytes, path)?;
    check_dwa_blocks(bytes, &meta, path)?;
    Ok(meta)
}

/// The file's headers, each checked ([`check_header`]); its blocks are not looked at.
fn checked_headers(bytes: &[u8], path: &Path) -> Result<exr::meta::MetaData> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| cannot_read(path, e))?;
    for header in meta.headers.iter() {
        check_header(header, bytes.len(), path)?;
    }
    if meta.headers.is_empty() {
        return Err(Error::format(path, "EXR file has no part; expected one"));
    }
    Ok(meta)
}

fn cannot_read(path: &Path, e: exr::error::Error) -> Error {
    let why = match e {
        // A feature the reader lacks (deep data, subsampled channels): not damage.
        exr::error::Error::NotSupported(_) => {
            "this OpenEXR feature is not read: save the image as a flat (not deep) scanline \
             or tiled image, each channel at full resolution"
        }
        _ => "the file may be truncated or corrupt",
    };
    Error::format(path, format!("cannot read as OpenEXR: {e}; {why}"))
}

pub(crate) fn parse_exr_scalar(bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    let meta = checked_meta(bytes, path)?;
    let channels = Channels::new(&meta);
    let chosen = channels.depth().ok_or_else(|| {
        Error::format(
            path,
            format!(
                "EXR channels are {}; expected a depth channel, in order of preference: {}",
                channels.list(),
                DEPTH_CHANNEL_ORDER
            ),
        )
    })?;
    if chosen.full != "Z" {
        log::info!("{}: depth from EXR channel {}", path.display(), chosen.full);
    }
    read_channel(chosen, bytes, path)
}

/// Decodes `chosen` alone (the other channels could hold many times its size), at full
/// resolution, as a map row 0 at the top.
fn read_channel(chosen: &Channel, bytes: &[u8], path: &Path) -> Result<ScalarMap> {
    full_resolution(chosen, path)?;
    let (w, h) = (
        chosen.header.layer_size.width(),
        chosen.header.layer_size.height(),
    );
    let pixels = decode_pixels([chosen], bytes, path, f32::NAN, |p, _, v| *p = v)?;
    Ok(Grid::from_vec(w, h, pixels))
}

/// A colour image read from an EXR file, and where in the file it was found.
pub(crate) struct ExrColour {
    /// The pixels, linear as stored, row 0 at the top.
    pub image: RgbImage,
    /// Which channels they came from, for the log: `R, G, B`,
    /// `ViewLayer.Combined.R, .G, .B` or `Y (grey)`.
    pub source: String,
    /// The file's `chromaticities` attribute (CIE xy of red, green, blue and white), where
    /// it has one: the primaries its values are in.
    pub chromaticities: Option<[[f64; 2]; 4]>,
}

/// What [`parse_exr_rgb`] reads, for messages.
const EXR_COLOUR_CHANNELS: &str = "R, G and B (flat, or a layer's <layer>.R, \
     <layer>.G, <layer>.B such as ViewLayer.Combined.R), or a single Y channel (grey)";

/// Reads a colour image from an OpenEXR file, values as stored (linear), alpha and every
/// other channel ignored: the `R`, `G`, `B` of one layer, the flat ones first, then the
/// first layer with `Combined` in its path (Blender's beauty pass), then the first layer
/// that has all three; failing that, a flat `Y` (luminance) as grey, unless it is a
/// vector's (beside an `X`).
pub(crate) fn parse_exr_rgb(bytes: &[u8], path: &Path) -> Result<ExrColour> {
    let meta = checked_meta(bytes, path)?;
    let channels = Channels::new(&meta);
    let chromaticities = meta.headers[0]
        .shared_attributes
        .chromaticities
        .map(|c| [c.red, c.green, c.blue, c.white].map(|v| [f64::from(v.0), f64::from(v.1)]));
    let (image, source) = match colour_channels(&channels, path)? {
        ColourChannels::Rgb([r, g, b]) => {
            let (w, h) = (r.header.layer_size.width(), r.header.layer_size.height());
            // Only the three channels are kept: a multilayer file holds many more.
            let pixels = decode_pixels([r, g, b], bytes, path, [f32::NAN; 3], |p, i, v| p[i] = v)?;
            let source = match r.layer() {
                "" => "R, G, B".to_string(),
                layer => format!("{layer}.R, .G, .B"),
            };
            (Grid::from_vec(w, h, pixels), source)
        }
        ColourChannels::Grey(y) => {
            let (w, h) = (y.header.layer_size.width(), y.header.layer_size.height());
            let pixels = decode_pixels([y], bytes, path, [f32::NAN; 3], |p, _, v| *p = [v; 3])?;
            (Grid::from_vec(w, h, pixels), "Y (grey)".to_string())
        }
    };
    Ok(ExrColour {
        image,
        source,
        chromaticities,
    })
}

/// The size of the colour image [`parse_exr_rgb`] reads from the EXR file `bytes`, from
/// its headers alone (every one checked as [`parse_exr_rgb`] checks them; no block is
/// read): for a check of the memory the work on it needs, before it is decoded.
pub(crate) fn exr_colour_size(bytes: &[u8], path: &Path) -> Result<(usize, usize)> {
    let meta = checked_headers(bytes, path)?;
    let channels = Channels::new(&meta);
    let size = match colour_channels(&channels, path)? {
        ColourChannels::Rgb([r, ..]) => r.header.layer_size,
        ColourChannels::Grey(y) => y.header.layer_size,
    };
    Ok((size.width(), size.height()))
}

/// The size of the depth channel [`parse_exr_scalar`] reads from the EXR file `bytes`,
/// from its headers alone, if they can be read and name one (else the decoder's error).
pub(crate) fn exr_depth_size(bytes: &[u8], path: &Path) -> Option<(usize, usize)> {
    let meta = checked_headers(bytes, path).ok()?;
    let size = Channels::new(&meta).depth()?.header.layer_size;
    Some((size.width(), size.height()))
}

/// The channels an EXR file's colour is read from.
enum ColourChannels<'c, 'm> {
    /// One layer's `R`, `G` and `B`.
    Rgb([&'c Channel<'m>; 3]),
    /// A flat `Y`, as grey.
    Grey(&'c Channel<'m>),
}

/// The colour channels of `channels`, chosen as [`parse_exr_rgb`] says, each at full
/// resolution; an error saying what the file has instead when there are none.
fn colour_channels<'c, 'm>(
    channels: &'c Channels<'m>,
    path: &Path,
) -> Result<ColourChannels<'c, 'm>> {
    if let Some(rgb) = channels.rgb() {
        for c in rgb {
            full_resolution(c, path)?;
        }
        return Ok(ColourChannels::Rgb(rgb));
    }
    // Luminance-chroma images keep their colour in subsampled RY and BY channels; their Y
    // alone would silently lose it.
    let chroma = channels
        .first(|c| matches!(c.full.as_str(), "RY" | "BY"))
        .is_some();
    let grey = channels.first(|c| c.full == "Y" && channels.sibling(c, "X").is_none());
    if let Some(y) = grey.filter(|_| !chroma) {
        full_resolution(y, path)?;
        return Ok(ColourChannels::Grey(y));
    }
    // The depth rules take a lone channel of any name: point at depth only when named so.
    let depth = channels
        .depth()
        .filter(|c| c.leaf() == "Z" || c.full.eq_ignore_ascii_case("depth"));
    let hint = match (chroma, depth) {
        (true, _) => "; luminance-chroma (Y, RY, BY) images are not read: save it as RGB".into(),
        (false, Some(depth)) => format!(
            "; it has depth ({}) but no colour: give it as the depth map, with a colour image",
            depth.full
        ),
        (false, None) => String::new(),
    };
    Err(Error::format(
        path,
        format!(
            "EXR channels are {}; expected colour channels {EXR_COLOUR_CHANNELS}{hint}",
            channels.list()
        ),
    ))
}

/// Refuses a subsampled channel: only full-resolution ones line up with the pixels.
fn full_resolution(c: &Channel, path: &Path) -> Result<()> {
    let description = c
        .header
        .channels
        .list
        .iter()
        .find(|d| &d.name == c.text)
        .expect("the channel comes from this header");
    let (sx, sy) = (description.sampling.x(), description.sampling.y());
    if (sx, sy) != (1, 1) {
        let (w, h) = (c.header.layer_size.width(), c.header.layer_size.height());
        return Err(Error::format(
            path,
            format!(
                "EXR channel {} is subsampled ({sx}x{sy} pixels per sample for {w}x{h} pixels); expected full resolution",
                c.full
            ),
        ));
    }
    Ok(())
}

/// Decodes `channels`, all of one part, at full resolution into pixels of type `P`, row 0
/// at the top: each starts as `empty` (where the file has no block) and `set(pixel, i, v)`
/// stores the value `v` of `channels[i]`. Blocks are decoded in parallel on brume's pool
/// and copied out as each is done, so only the pixels asked for are held. The decoder
/// runs inside `catch_unwind`: a file it cannot handle is an error, not the end of the
/// program (exr's own parallel decoder runs on threads where a panic aborts).
fn decode_pixels<P: Copy + Send, const N: usize>(
    channels: [&Channel; N],
    bytes: &[u8],
    path: &Path,
    empty: P,
    set: impl Fn(&mut P, usize, f32) + Sync,
) -> Result<Vec<P>> {
    let header = channels[0].header;
    let part = channels[0].part;
    let (w, h) = (header.layer_size.width(), header.layer_size.height());
    let wanted: [usize; N] = channels.map(|c| {
        let list = &header.channels.list;
        list.iter()
            .position(|d| &d.name == c.text)
            .expect("the channel is the part's")
    });
    let chunks = exr::block::read(Cursor::new(bytes), false)
        .and_then(|reader| {
            reader.filter_chunks(false, |_, tile, block| {
                block.layer == part && tile.is_largest_resolution_level()
            })
        })
        .map_err(|e| cannot_read(path, e))?;
    let meta = exr::block::reader::ChunksReader::meta_data(&chunks).clone();
    let pixels = std::sync::Mutex::new(vec![empty; w * h]);
    let decode = || {
        chunks.par_bridge().try_for_each(|chunk| {
            let block = exr::block::UncompressedBlock::decompress_chunk(chunk?, &meta, false)?;
            let (lines, values) = block_lines(&block, &header.channels, &wanted, w, h)?;
            let mut pixels = pixels.lock().unwrap_or_else(|e| e.into_inner());
            for (channel, start, range) in lines {
                let line = pixels[start..start + range.len()].iter_mut();
                line.zip(&values[range])
                    .for_each(|(p, &v)| set(p, channel, v));
            }
            Ok(())
        })
    };
    match std::panic::catch_unwind(AssertUnwindSafe(|| crate::parallel::run(decode))) {
        Ok(decoded) => decoded.map_err(|e| cannot_read(path, e))?,
        Err(panic) => return Err(decoder_panicked(path, panic.as_ref())),
    }
    Ok(pixels.into_inner().unwrap_or_else(|e| e.into_inner()))
}

/// A line of a block: the index of its channel in `wanted`, where it starts in the
/// `width`x`height` pixels, and where its values are in the block's values.
type BlockLine = (usize, usize, std::ops::Range<usize>);

/// The lines of `block` in the channels `wanted` (indices into `channels`), and their
/// values as f32. A line outside the pixels is an error.
fn block_lines(
    block: &exr::block::UncompressedBlock,
    channels: &ChannelList,
    wanted: &[usize],
    width: usize,
    height: usize,
) -> exr::error::Result<(Vec<BlockLine>, Vec<f32>)> {
    use exr::meta::attribute::SampleType;
    let (mut lines, mut values) = (Vec::new(), Vec::new());
    let mut halves = Vec::new();
    for line in block.lines(channels) {
        let at = line.location;
        let Some(channel) = wanted.iter().position(|&c| c == at.channel) else {
            continue;
        };
        let (x, y, n) = (at.position.x(), at.position.y(), at.sample_count);
        if y >= height || x.checked_add(n).is_none_or(|end| end > width) {
            return Err(exr::error::Error::Invalid("block outside the layer".into()));
        }
        let first = values.len();
        values.resize(first + n, 0.0);
        let out = &mut values[first..];
        match channels.list[at.channel].sample_type {
            SampleType::F32 => line.read_samples_into_slice(out)?,
            SampleType::F16 => {
                halves.resize(n, half::f16::ZERO);
                line.read_samples_into_slice(&mut halves[..])?;
                half::slice::HalfFloatSliceExt::convert_to_f32_slice(&halves[..], out);
            }
            SampleType::U32 => {
                for (o, v) in out.iter_mut().zip(line.read_samples::<u32>()) {
                    *o = v? as f32;
                }
            }
        }
        lines.push((channel, y * width + x, first..first + n));
    }
    Ok((lines, values))
}

/// The error for a panic inside exr's decoder: a file it could not handle, which must not
/// end the program of a library's host.
fn decoder_panicked(path: &Path, panic: &(dyn std::any::Any + Send)) -> Error {
    let what = panic
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| panic.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "no message".into());
    Error::format(
        path,
        format!(
            "the OpenEXR decoder failed on this file ({what}); it is corrupt, or uses a \
             feature the decoder cannot handle: re-save it, e.g. with `oiiotool in.exr \
             --compression zip -o out.exr`"
        ),
    )
}

/// The most bytes one block of an EXR part may decode to: 256 rows (DWAB's blocks) of a
/// 16384-pixel-wide image ([`crate::io::limits::MAX_SIDE`]) with 64 float channels. exr
/// decodes a block whole, every channel of it, and allocates its size before reading its
/// data: a file of a few bytes could claim hundreds of channels, and a failed allocation
/// aborts the process.
pub const MAX_EXR_BLOCK_BYTES: u64 = 1 << 30;

/// Refuses a layer whose claimed size is beyond `io::limits`, whose blocks decode to more
/// than [`MAX_EXR_BLOCK_BYTES`] each, or which the file is too short to hold: every chunk
/// takes an 8-byte offset and an 8-byte chunk header at least, and uncompressed pixels take
/// their full size.
fn check_header(header: &exr::meta::header::Header, file_len: usize, path: &Path) -> Result<()> {
    let size = header.layer_size;
    check_size(path, "EXR", size.width() as u64, size.height() as u64)?;
    check_block_bytes(header, path)?;
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

/// Refuses a part whose largest block decodes to more than [`MAX_EXR_BLOCK_BYTES`].
fn check_block_bytes(header: &Header, path: &Path) -> Result<()> {
    use exr::meta::BlockDescription;
    let (w, h) = (header.layer_size.width(), header.layer_size.height());
    let (block_w, block_h) = match header.blocks {
        BlockDescription::ScanLines => (w, header.compression.scan_lines_per_block()),
        BlockDescription::Tiles(t) => (t.tile_size.width(), t.tile_size.height()),
    };
    let (block_w, block_h) = (block_w.min(w) as u64, block_h.min(h) as u64);
    let per_pixel = header.channels.bytes_per_pixel as u64;
    let bytes = (block_w * block_h).saturating_mul(per_pixel);
    if bytes > MAX_EXR_BLOCK_BYTES {
        return Err(Error::format(
            path,
            format!(
                "EXR blocks of {block_w}x{block_h} pixels of {} channels ({per_pixel} bytes \
                 a pixel, {}) decode to {bytes} bytes each, more than the {MAX_EXR_BLOCK_BYTES} \
                 brume decodes at once; the file is corrupt, or re-save it with fewer \
                 channels or smaller blocks, e.g. `oiiotool in.exr --compression zip -o \
                 out.exr` (16 rows a block)",
                header.channels.list.len(),
                header.compression
            ),
        ));
    }
    Ok(())
}

/// Whether a part is DWA-compressed (lossy DCT for colour channels, RLE or zlib for the
/// others).
fn is_dwa(compression: exr::compression::Compression) -> bool {
    use exr::compression::Compression::{DWAA, DWAB};
    matches!(compression, DWAA(_) | DWAB(_))
}

/// Checks the sizes every block of a DWA part claims before the decoder sees them. exr's
/// DWA decoder (new in 1.74) allocates what a block's header claims before checking it: a
/// damaged 1,199-byte file asked for 1.7 PB, and a failed allocation aborts the process
/// (found by the `exr` fuzzer, `tests/data/fuzz/depth-exr-dwa-claims-1.7-petabytes.exr`).
/// No other compression does. The chunks are found as the decoder finds them, through
/// the offset tables, so a block it decodes is a block checked here.
fn check_dwa_blocks(bytes: &[u8], meta: &exr::meta::MetaData, path: &Path) -> Result<()> {
    use exr::block::chunk::CompressedBlock;
    if !meta.headers.iter().any(|h| is_dwa(h.compression)) {
        return Ok(());
    }
    let chunks = exr::block::read(Cursor::new(bytes), false)
        .and_then(|reader| reader.filter_chunks(false, |_, _, _| true))
        .map_err(|e| cannot_read(path, e))?;
    for chunk in chunks {
        let chunk = chunk.map_err(|e| cannot_read(path, e))?;
        let Some(header) = meta.headers.get(chunk.layer_index) else {
            continue; // the decoder refuses it
        };
        if !is_dwa(header.compression) {
            continue;
        }
        let data = match &chunk.compressed_block {
            CompressedBlock::ScanLine(b) => &b.compressed_pixels_le,
            CompressedBlock::Tile(t) => &t.compressed_pixels_le,
            _ => continue, // deep data: refused by the decoder
        };
        let bounds = header
            .get_block_data_indices(&chunk.compressed_block)
            .and_then(|tile| header.get_absolute_block_pixel_coordinates(tile))
            .map_err(|e| cannot_read(path, e))?;
        let (w, h) = (bounds.size.width(), bounds.size.height());
        let channels = &header.channels;
        if let Some(claim) =
            dwa_over_claim(data, w, h, channels.list.len(), channels.bytes_per_pixel)
        {
            return Err(Error::format(
                path,
                format!(
                    "EXR block at row {} ({w}x{h} pixels, {}) claims {claim}; the file \
                     is corrupt",
                    bounds.position.y(),
                    header.compression
                ),
            ));
        }
    }
    Ok(())
}

/// The first size in a DWA block's header (OpenEXR's `DataSizesSingle`: eleven
/// little-endian `u64`) that no block of `width`x`height` pixels of `channels` channels
/// can need, described; `None` when all fit, or when the block is stored raw or too short
/// to hold the header (the decoder reads those itself). The bounds are what OpenEXR's
/// encoder can write at most: raw and zlib-packed channel data no larger than the pixels,
/// run-length tokens at most two bytes per byte, one DC and 63 AC coefficients per 8x8
/// block of each channel.
fn dwa_over_claim(
    data: &[u8],
    width: usize,
    height: usize,
    channels: usize,
    bytes_per_pixel: usize,
) -> Option<String> {
    const UNKNOWN_UNCOMPRESSED: usize = 1;
    const RLE_UNCOMPRESSED: usize = 6;
    const RLE_RAW: usize = 7;
    const AC_COUNT: usize = 8;
    const DC_COUNT: usize = 9;
    let pixel_bytes = width.saturating_mul(height).saturating_mul(bytes_per_pixel) as u64;
    if data.len() as u64 == pixel_bytes || data.len() < 11 * 8 {
        return None;
    }
    let counter = |i: usize| {
        let field: [u8; 8] = data[i * 8..i * 8 + 8].try_into().expect("8 bytes");
        u64::from_le_bytes(field)
    };
    let blocks = width.div_ceil(8).saturating_mul(height.div_ceil(8));
    let blocks = blocks.saturating_mul(channels) as u64;
    let limits = [
        (
            UNKNOWN_UNCOMPRESSED,
            "bytes of raw channel data",
            pixel_bytes,
        ),
        (
            RLE_UNCOMPRESSED,
            "bytes of run-length tokens",
            pixel_bytes.saturating_mul(2),
        ),
        (RLE_RAW, "bytes of run-length data", pixel_bytes),
        (AC_COUNT, "AC coefficients", blocks.saturating_mul(63)),
        (DC_COUNT, "DC coefficients", blocks),
    ];
    limits.into_iter().find_map(|(i, what, most)| {
        let claimed = counter(i);
        (claimed > most).then(|| format!("{claimed} {what}, more than the {most} it can hold"))
    })
}

/// Writes an RGBA image as four 32-bit channels `R`, `G`, `B`, `A`, with a
/// `chromaticities` attribute (CIE xy of red, green, blue and white) where given: without
/// one, OpenEXR's primaries are Rec. 709's (sRGB's).
pub(crate) fn write_rgba(
    out: &mut BufWriter<&File>,
    img: &RgbaImage,
    chromaticities: Option<[[f64; 2]; 4]>,
) -> std::io::Result<()> {
    let channel = |c: usize| img.as_slice().iter().map(|p| p[c]).collect::<Vec<f32>>();
    let channels = [
        ("R", channel(0)),
        ("G", channel(1)),
        ("B", channel(2)),
        ("A", channel(3)),
    ];
    write_exr(out, img.width(), img.height(), channels, chromaticities)
}

/// Writes a scalar map as one 32-bit channel named `Y`, which [`read_exr_scalar`] reads
/// back.
pub(crate) fn write_scalar(out: &mut BufWriter<&File>, map: &ScalarMap) -> std::io::Result<()> {
    let channels = [("Y", map.as_slice().to_vec())];
    write_exr(out, map.width(), map.height(), channels, None)
}

fn write_exr<const N: usize>(
    out: &mut BufWriter<&File>,
    width: usize,
    height: usize,
    channels: [(&str, Vec<f32>); N],
    chromaticities: Option<[[f64; 2]; 4]>,
) -> std::io::Result<()> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, SmallVec,
        WritableImage,
    };
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|(name, data)| AnyChannel::new(name, FlatSamples::F32(data)))
        .collect();
    // Tiles in increasing order, not as the parallel compression finishes them: the same
    // pixels give the same bytes (a dataset's checksums, a resumed batch's outputs).
    let encoding = Encoding {
        line_order: exr::meta::attribute::LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(list),
    );
    let mut image = Image::from_layer(layer);
    image.attributes.chromaticities = chromaticities.map(|[r, g, b, w]| {
        let xy = |[x, y]: [f64; 2]| exr::math::Vec2(x as f32, y as f32);
        exr::meta::attribute::Chromaticities {
            red: xy(r),
            green: xy(g),
            blue: xy(b),
            white: xy(w),
        }
    });
    image.write().to_buffered(out).map_err(|e| match e {
        // The OS error as it is: a full disk must stay a full disk (`is_out_of_space`).
        exr::error::Error::Io(io) => io,
        e => std::io::Error::other(format!("OpenEXR encoder: {e}")),
    })
}

/// Reads the first channel (in [`Channels`] order) whose full name (`part.layer.leaf`)
/// `pick` accepts, with its name; `None` when no channel is accepted. For the channels
/// beside a colour image: its alpha, its depth (`photo::insert`).
pub(crate) fn parse_exr_channel(
    bytes: &[u8],
    path: &Path,
    pick: impl Fn(&str) -> bool,
) -> Result<Option<(String, ScalarMap)>> {
    let meta = checked_meta(bytes, path)?;
    let channels = Channels::new(&meta);
    let Some(chosen) = channels.first(|c| pick(&c.full)) else {
        return Ok(None);
    };
    Ok(Some((
        chosen.full.clone(),
        read_channel(chosen, bytes, path)?,
    )))
}
