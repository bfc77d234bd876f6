//! Datasets of RGBD frames to fog in bulk (`brume batch`): Cityscapes triplets found under
//! folders, or the rows of a CSV manifest; deterministic shards for array jobs; Foggy
//! Cityscapes' output names; and the whole run ([`Batch`]).

mod batch;
mod destinations;
mod report;
mod settings;
mod writer;

pub use batch::{
    check_beta, default_loaders, default_writers, Batch, BatchOptions, Betas, MAX_BETA,
    MAX_LOADERS, MAX_WRITERS, MIN_BETA,
};
pub use report::{BatchEvent, BatchReport};
pub use settings::{settings_of, SETTINGS_FILE};

use crate::error::{Error, Result};
use crate::photo::BetaDistribution;
use std::path::{Component, Path, PathBuf};

/// Cityscapes' suffix of a left image: `{name}_leftImg8bit.png`.
pub const CITYSCAPES_IMAGE_SUFFIX: &str = "_leftImg8bit.png";

/// One frame of a dataset and the files that go with it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Item {
    /// The colour image.
    pub image: PathBuf,
    /// The depth, range or disparity map.
    pub depth: PathBuf,
    /// Cityscapes camera JSON (intrinsics, baseline), where there is one.
    pub camera: Option<PathBuf>,
    /// Middlebury calib.txt, where there is one.
    pub calib: Option<PathBuf>,
    /// A semantic sky mask (binary, or Cityscapes labelIds), where there is one.
    pub sky_mask: Option<PathBuf>,
    /// The folder of the outputs, relative to `--out`: the image's folder relative to the
    /// root it was found under (the input tree, mirrored).
    pub out_dir: PathBuf,
    /// The image's file name without its extension (`{name}_leftImg8bit`): outputs are
    /// named after it.
    pub stem: String,
}

impl Item {
    /// The key that orders items and assigns them to shards: the output folder and stem,
    /// which do not depend on where the dataset is mounted.
    pub fn key(&self) -> String {
        let dir: Vec<String> = self
            .out_dir
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        format!("{}/{}", dir.join("/"), self.stem)
    }

    /// Foggy Cityscapes' name of the output at extinction `beta` (m⁻¹):
    /// `{out}/{out_dir}/{stem}_foggy_beta_{beta}.png`.
    pub fn foggy_output(&self, out: &Path, beta: f64) -> PathBuf {
        out.join(&self.out_dir)
            .join(format!("{}_foggy_beta_{}.png", self.stem, beta_label(beta)))
    }

    /// A fixed 64-bit hash (FNV-1a) of the output folder and stem: the same on every run,
    /// platform and shard. It picks the frame's β from a distribution ([`Item::drawn_beta`])
    /// and seeds its capture noise.
    pub fn name_hash(&self) -> u64 {
        let name = format!("{}/{}", self.out_dir.display(), self.stem);
        name.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        })
    }

    /// This frame's β drawn from `dist` under `seed` (`brume batch --beta-dist`): a
    /// function of the frame's name alone, whatever the order or shard it is rendered in,
    /// rounded to 6 significant digits for its file name.
    pub fn drawn_beta(&self, dist: &BetaDistribution, seed: u64) -> f64 {
        let beta = dist.sample(seed, self.name_hash());
        format!("{beta:.5e}").parse().unwrap_or(beta)
    }

    /// The transmittance map beside it: `{stem}_transmittance_beta_{beta}.png`.
    pub fn transmittance_output(&self, out: &Path, beta: f64) -> PathBuf {
        out.join(&self.out_dir).join(format!(
            "{}_transmittance_beta_{}.png",
            self.stem,
            beta_label(beta)
        ))
    }
}

/// β as Foggy Cityscapes writes it in file names: the shortest decimal (`0.005`, `0.01`).
pub fn beta_label(beta: f64) -> String {
    format!("{beta}")
}

/// A deterministic 1/N of the work: shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, 1..=count.
    pub index: u32,
    /// How many shards the work is split into.
    pub count: u32,
}

impl Shard {
    /// The whole of the work.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Parses `K/N` with 1 ≤ K ≤ N, or `slurm` for [`Shard::from_slurm`] with the
    /// process's environment.
    pub fn parse(text: &str) -> Result<Self> {
        if text.trim() == "slurm" {
            return Self::from_slurm(|name| std::env::var(name).ok());
        }
        let bad = || {
            Error::invalid(
                "shard",
                text,
                "K/N with 1 ≤ K ≤ N (e.g. 3/8), or slurm in a task of a Slurm job array",
            )
        };
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) = match (k.trim().parse::<u32>(), n.trim().parse::<u32>()) {
            (Ok(k), Ok(n)) if k >= 1 && k <= n => (k, n),
            _ => return Err(bad()),
        };
        Ok(Shard { index, count })
    }

    /// Whether `item` belongs to this shard. By a hash of the item's key, not its place in
    /// a list: every shard decides alone, and adding frames to a dataset moves no other
    /// frame to another shard.
    ///
    /// The hash is FNV-1a mixed by SplitMix64's finaliser: raw FNV-1a's low bits follow the
    /// last bytes of the key, so consecutive frame names fell into every other shard
    /// (8 frames over 4 shards: 0/4/0/4). Shard membership changed with the mixing.
    pub fn contains(&self, item: &Item) -> bool {
        let hash = splitmix64_finish(fnv1a(item.key().as_bytes()));
        hash % u64::from(self.count) == u64::from(self.index - 1)
    }

    /// This task's shard of a Slurm job array, from the variables Slurm sets in each task:
    /// `SLURM_ARRAY_TASK_ID`, `_MIN`, `_STEP` (default 1) and `_COUNT`. Any array works
    /// (`--array=0-15`, `1-16`, `0-30:2`): the task's place in it is the shard.
    pub fn from_slurm(var: impl Fn(&str) -> Option<String>) -> Result<Self> {
        let number = |name: &str| -> Result<Option<u64>> {
            match var(name) {
                None => Ok(None),
                Some(text) => text.trim().parse::<u64>().map(Some).map_err(|_| {
                    Error::invalid(
                        "shard",
                        format!("slurm: {name}={text}"),
                        "a whole number, as Slurm sets it in each task of a job array",
                    )
                }),
            }
        };
        let missing = || {
            Error::invalid(
                "shard",
                "slurm: SLURM_ARRAY_TASK_ID, _MIN or _COUNT unset",
                "a task of a Slurm job array (sbatch --array=...)",
            )
        };
        let id = number("SLURM_ARRAY_TASK_ID")?.ok_or_else(missing)?;
        let min = number("SLURM_ARRAY_TASK_MIN")?.ok_or_else(missing)?;
        let count = number("SLURM_ARRAY_TASK_COUNT")?.ok_or_else(missing)?;
        let step = number("SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
        let place = id
            .checked_sub(min)
            .filter(|d| d % step == 0)
            .map(|d| d / step + 1);
        match (place, u32::try_from(count)) {
            (Some(index), Ok(count)) if index <= u64::from(count) => Ok(Shard {
                index: index as u32,
                count,
            }),
            _ => Err(Error::invalid(
                "shard",
                format!("slurm: task {id} of an array from {min} by {step}, {count} tasks"),
                "an array of evenly spaced task ids (`--array=1-16` or `0-30:2`, not a \
                 list): use a K/N shard",
            )),
        }
    }
}

/// SplitMix64's output function: every input bit moves every output bit.
fn splitmix64_finish(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// FNV-1a, 64 bits: stable across platforms and releases (std's hasher is not).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// The Cityscapes frames under `root`: every `{name}_leftImg8bit.png`, with
/// `{name}_disparity.png` and `{name}_camera.json` beside it or in Cityscapes' own layout
/// (`leftImg8bit/{split}/{city}/` ↔ `disparity/…`, `camera/…`), and the sky from
/// `gtFine/…/{name}_gtFine_labelIds.png` where that exists. Frames whose disparity or
/// camera is missing come back as errors, one per frame, so that a run can report and
/// skip them.
pub fn find_cityscapes(root: &Path) -> Result<Vec<std::result::Result<Item, Error>>> {
    let mut images = Vec::new();
    crate::io::visit_files(root, &mut |entry, _| {
        if entry
            .file_name()
            .to_string_lossy()
            .ends_with(CITYSCAPES_IMAGE_SUFFIX)
        {
            images.push(entry.path());
        }
        Ok(())
    })?;
    images.sort();
    Ok(images
        .iter()
        .map(|image| cityscapes_item(root, image))
        .collect())
}

fn cityscapes_item(root: &Path, image: &Path) -> std::result::Result<Item, Error> {
    let file = image
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = file.trim_end_matches(CITYSCAPES_IMAGE_SUFFIX);
    let companion = |folder: &str, suffix: &str| -> Vec<PathBuf> {
        let file_name = format!("{name}{suffix}");
        let beside = image.with_file_name(&file_name);
        let mut candidates = vec![beside];
        if let Some(mirrored) = swap_component(image, "leftImg8bit", folder) {
            candidates.push(mirrored.with_file_name(&file_name));
        }
        candidates
    };
    let find = |folder: &str, suffix: &str, what: &str| -> std::result::Result<PathBuf, Error> {
        let candidates = companion(folder, suffix);
        candidates
            .iter()
            .find(|p| p.is_file())
            .cloned()
            .ok_or_else(|| Error::Format {
                path: image.to_path_buf(),
                detail: format!(
                    "no {what} for this frame (looked for {})",
                    candidates
                        .iter()
                        .map(|p| p.display().to_string())
                        .collect::<Vec<_>>()
                        .join(" and ")
                ),
            })
    };
    let depth = find("disparity", "_disparity.png", "disparity")?;
    let camera = find("camera", "_camera.json", "camera file")?;
    let sky_mask = companion("gtFine", "_gtFine_labelIds.png")
        .into_iter()
        .find(|p| p.is_file());
    let out_dir = image
        .parent()
        .and_then(|p| p.strip_prefix(root).ok())
        .map(Path::to_path_buf)
        .unwrap_or_default();
    Ok(Item {
        image: image.to_path_buf(),
        depth,
        camera: Some(camera),
        calib: None,
        sky_mask,
        out_dir,
        stem: file.trim_end_matches(".png").to_string(),
    })
}

/// `path` with its last component named `from` renamed `to`, if it has one.
fn swap_component(path: &Path, from: &str, to: &str) -> Option<PathBuf> {
    let parts: Vec<Component> = path.components().collect();
    let at = parts.iter().rposition(|c| c.as_os_str() == from)?;
    let mut swapped = PathBuf::new();
    for (i, c) in parts.iter().enumerate() {
        if i == at {
            swapped.push(to);
        } else {
            swapped.push(c.as_os_str());
        }
    }
    Some(swapped)
}

/// The frames of a CSV manifest: a header naming the columns `image` (required), `depth`
/// (required but for portrait JPEGs) and `camera`, `calib`, `sky_mask` (optional; empty
/// cells allowed), then one row per frame. A JPEG image without a depth cell (or column)
/// is its own depth file: a phone's portrait photo, which carries its depth map. Relative
/// paths are relative to the manifest's folder; outputs mirror the images' folders
/// relative to it. See [`parse_manifest`].
pub fn read_manifest(path: &Path) -> Result<Vec<Item>> {
    let text = crate::io::limits::read_text(path)?;
    parse_manifest(&text, path)
}

/// [`read_manifest`] on the text of a manifest; `path` is the manifest's path, which names
/// it in errors and whose folder relative paths are resolved against. Blank lines and
/// lines starting with `#` are skipped, and a leading byte-order mark (as spreadsheets
/// write) is ignored. Errors: no header, an unknown or repeated column, no `image`
/// column, a header and no rows, a row with another number of cells than the header, an
/// empty image cell, no depth for an image that is not a JPEG. Every item returned has a
/// non-empty image and depth path (the image's own, for a portrait JPEG without one).
pub fn parse_manifest(text: &str, path: &Path) -> Result<Vec<Item>> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let base = path.parent().unwrap_or(Path::new("."));
    let bad = |detail: String| Error::Format {
        path: path.to_path_buf(),
        detail,
    };
    let mut records = manifest_records(text)
        .map_err(|e| bad(format!("not CSV: {e}")))?
        .into_iter();
    let Some((_, header_cells)) = records.next() else {
        return Err(bad(
            "empty manifest: expected a header `image,depth[,camera][,calib][,sky_mask]`".into(),
        ));
    };
    let header = header_cells.join(",");
    let columns: Vec<String> = header_cells.iter().map(|c| c.to_lowercase()).collect();
    let column = |name: &str| columns.iter().position(|c| c == name);
    for (i, c) in columns.iter().enumerate() {
        if !["image", "depth", "camera", "calib", "sky_mask"].contains(&c.as_str()) {
            return Err(bad(format!(
                "unknown column `{c}`: expected image, depth, camera, calib, sky_mask"
            )));
        }
        if columns[..i].contains(c) {
            return Err(bad(format!(
                "the header `{header}` names the column `{c}` twice"
            )));
        }
    }
    let Some(image_col) = column("image") else {
        return Err(bad(format!(
            "the header `{header}` lacks the column `image`"
        )));
    };
    let folder = absolute(base);
    let mut items = Vec::new();
    for (line, cells) in records {
        if cells.len() != columns.len() {
            return Err(bad(format!(
                "line {line}: {} cells, expected {} (as the header)",
                cells.len(),
                columns.len()
            )));
        }
        let cell = |i: Option<usize>| {
            i.map(|i| cells[i].as_str())
                .filter(|c| !c.is_empty())
                .map(|c| base.join(c))
        };
        let Some(image) = cell(Some(image_col)) else {
            return Err(bad(format!("line {line}: the image cell is empty")));
        };
        let Some(depth) = cell(column("depth")).or_else(|| is_jpeg(&image).then(|| image.clone()))
        else {
            return Err(bad(format!(
                "line {line}: no depth for {}: expected a depth file in the `depth` cell (only \
                 a phone's portrait JPEG carries its own depth map)",
                image.display()
            )));
        };
        let out_dir = folder_under(&image, &folder);
        let stem = image
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        items.push(Item {
            image,
            depth,
            camera: cell(column("camera")),
            calib: cell(column("calib")),
            sky_mask: cell(column("sky_mask")),
            out_dir,
            stem,
        });
    }
    if items.is_empty() {
        return Err(bad(format!(
            "the manifest has a header but no rows: expected one row per frame after \
             `{header}`"
        )));
    }
    Ok(items)
}

/// Whether a path names a JPEG by its extension.
fn is_jpeg(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("jpg") || e.eq_ignore_ascii_case("jpeg"))
}

/// The records of a manifest's CSV text with their line numbers, cells trimmed (quoted
/// cells as CSV quotes them); blank lines and lines starting with `#` are skipped.
fn manifest_records(text: &str) -> std::result::Result<Vec<(u64, Vec<String>)>, csv::Error> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let mut records = Vec::new();
    for record in reader.records() {
        let record = record?;
        if record.iter().all(str::is_empty) {
            continue;
        }
        let line = record.position().map_or(0, |p| p.line());
        records.push((line, record.iter().map(str::to_owned).collect()));
    }
    Ok(records)
}

/// `path` made absolute against the working folder without touching the file system
/// (`.` for an empty path), so that how a path was typed does not change what it names.
fn absolute(path: &Path) -> PathBuf {
    let path = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

/// The folder of `image` relative to `folder`, the manifest's folder made [`absolute`],
/// so that how the manifest's path was typed does not matter; empty for an image outside
/// that folder, whose outputs go to the output root.
fn folder_under(image: &Path, folder: &Path) -> PathBuf {
    absolute(image)
        .parent()
        .and_then(|parent| parent.strip_prefix(folder).ok())
        .map(Path::to_path_buf)
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(dir: &str, stem: &str) -> Item {
        Item {
            image: PathBuf::from(format!("/data/{dir}/{stem}.png")),
            depth: PathBuf::from("d.png"),
            camera: None,
            calib: None,
            sky_mask: None,
            out_dir: PathBuf::from(dir),
            stem: stem.into(),
        }
    }

    /// A frame's β depends on its name and the seed, not on where the dataset lies, and
    /// is rounded for its file name; the hash is FNV-1a's (one step from its offset basis
    /// for the name "/" of an item with no folder and no stem).
    #[test]
    fn a_frames_beta_follows_its_name() {
        let dist: BetaDistribution = "uniform:0.005,0.02".parse().unwrap();
        let a = item("aachen", "a_leftImg8bit");
        let mut moved = a.clone();
        moved.image = PathBuf::from("/elsewhere/a_leftImg8bit.png");
        assert_eq!(a.drawn_beta(&dist, 7), moved.drawn_beta(&dist, 7));
        let betas: Vec<f64> = ["a", "b", "c", "d"]
            .iter()
            .map(|s| item("aachen", s).drawn_beta(&dist, 7))
            .collect();
        assert!(betas.windows(2).all(|w| w[0] != w[1]), "{betas:?}");
        assert_ne!(a.drawn_beta(&dist, 7), a.drawn_beta(&dist, 8));
        for b in betas {
            assert!((0.005..=0.02).contains(&b), "{b}");
            assert_eq!(b, format!("{b:.5e}").parse::<f64>().unwrap());
        }
        let bare = Item {
            out_dir: PathBuf::new(),
            stem: String::new(),
            ..item("", "")
        };
        let slash = 0xcbf2_9ce4_8422_2325u64 ^ u64::from(b'/');
        assert_eq!(bare.name_hash(), slash.wrapping_mul(0x0100_0000_01b3));
    }

    #[test]
    fn shards_partition_the_work() {
        let items: Vec<Item> = (0..500)
            .map(|i| {
                item(
                    "leftImg8bit/train/city",
                    &format!("city_{i:06}_leftImg8bit"),
                )
            })
            .collect();
        let n = 7;
        let mut counts = vec![0usize; n as usize];
        for it in &items {
            let owners: Vec<u32> = (1..=n)
                .filter(|&k| Shard { index: k, count: n }.contains(it))
                .collect();
            assert_eq!(owners.len(), 1, "{} belongs to {owners:?}", it.key());
            counts[owners[0] as usize - 1] += 1;
        }
        // Each shard gets about 1/7 of 500 (71): a hash, not a round robin.
        assert!(
            counts.iter().all(|&c| (45..=100).contains(&c)),
            "{counts:?}"
        );
        assert!(items.iter().all(|it| Shard::ALL.contains(it)));
    }

    #[test]
    fn the_shard_of_an_item_does_not_depend_on_where_the_dataset_lies() {
        let a = item("leftImg8bit/val/x", "x_1_leftImg8bit");
        let mut b = a.clone();
        b.image = PathBuf::from("/mnt/other/leftImg8bit/val/x/x_1_leftImg8bit.png");
        for k in 1..=5 {
            let s = Shard { index: k, count: 5 };
            assert_eq!(s.contains(&a), s.contains(&b));
        }
    }

    /// Consecutive frame names, a few at a time, spread over the shards as a uniform
    /// random assignment would: with raw FNV-1a, 8 consecutive frames over 4 shards left
    /// 2 shards empty every time (0/4/0/4).
    #[test]
    fn small_sets_spread_like_random_ones() {
        let (frames, shards, sets) = (8usize, 4u32, 200usize);
        let mut empty = 0usize;
        for set in 0..sets {
            let mut counts = vec![0usize; shards as usize];
            for f in 0..frames {
                let it = item(
                    "leftImg8bit/val/frankfurt",
                    &format!("frankfurt_{:06}_{:06}_leftImg8bit", set, 19 + f),
                );
                let k = (1..=shards)
                    .find(|&k| {
                        Shard {
                            index: k,
                            count: shards,
                        }
                        .contains(&it)
                    })
                    .unwrap();
                counts[k as usize - 1] += 1;
            }
            empty += counts.iter().filter(|&&c| c == 0).count();
        }
        // Uniform: P(a shard gets none of 8) = (3/4)^8 = 0.100, so 0.40 empty shards per
        // set, 80 over 200 sets (σ ≈ 8.5); raw FNV-1a gave 400.
        let expected = sets as f64 * f64::from(shards) * 0.75f64.powi(frames as i32);
        assert!(
            (empty as f64 - expected).abs() < 40.0,
            "{empty} empty shards over {sets} sets, a uniform hash gives about {expected:.0}"
        );
    }

    #[test]
    fn slurm_arrays_give_every_task_its_shard() {
        let env = |id: &str, min: &str, step: Option<&str>, count: &str| {
            let vars: Vec<(String, String)> = [
                ("SLURM_ARRAY_TASK_ID", Some(id)),
                ("SLURM_ARRAY_TASK_MIN", Some(min)),
                ("SLURM_ARRAY_TASK_STEP", step),
                ("SLURM_ARRAY_TASK_COUNT", Some(count)),
            ]
            .into_iter()
            .filter_map(|(k, v)| v.map(|v| (k.to_string(), v.to_string())))
            .collect();
            Shard::from_slurm(move |name| {
                vars.iter().find(|(k, _)| k == name).map(|(_, v)| v.clone())
            })
        };
        // --array=1-16: task 1 is shard 1 (the README's old `ID + 1` skipped it).
        assert_eq!(
            env("1", "1", None, "16").unwrap(),
            Shard {
                index: 1,
                count: 16
            }
        );
        assert_eq!(
            env("16", "1", None, "16").unwrap(),
            Shard {
                index: 16,
                count: 16
            }
        );
        assert_eq!(
            env("0", "0", Some("1"), "4").unwrap(),
            Shard { index: 1, count: 4 }
        );
        assert_eq!(
            env("30", "0", Some("2"), "16").unwrap(),
            Shard {
                index: 16,
                count: 16
            }
        );
        for bad in [
            env("3", "0", Some("2"), "16"),
            env("40", "1", None, "16"),
            env("x", "1", None, "16"),
        ] {
            let e = bad.unwrap_err().to_string();
            assert!(e.contains("shard = slurm: "), "{e}");
        }
        let unset = Shard::from_slurm(|_| None).unwrap_err().to_string();
        assert!(unset.contains("SLURM_ARRAY_TASK_ID"), "{unset}");
    }

    #[test]
    fn shard_syntax() {
        assert_eq!(Shard::parse("3/8").unwrap(), Shard { index: 3, count: 8 });
        for bad in ["0/4", "5/4", "3", "a/b", "1/0", "-1/4", ""] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("shard") && e.contains("K/N"), "{bad}: {e}");
        }
    }

    #[test]
    fn foggy_cityscapes_names() {
        let it = item(
            "leftImg8bit/train/aachen",
            "aachen_000000_000019_leftImg8bit",
        );
        assert_eq!(
            it.foggy_output(Path::new("out"), 0.02),
            Path::new(
                "out/leftImg8bit/train/aachen/aachen_000000_000019_leftImg8bit_foggy_beta_0.02.png"
            )
        );
        assert_eq!(beta_label(0.005), "0.005");
        assert_eq!(beta_label(0.01), "0.01");
    }

    #[test]
    fn manifests_are_parsed_against_their_folder() {
        let path = Path::new("/data/set/frames.csv");
        let text = "\u{feff}# frames\nImage, depth ,sky_mask\n\n\
                    left/a.png,depth/a.png,\n/abs/b.jpg,d/b.pfm,masks/b.png\n";
        let items = parse_manifest(text, path).unwrap();
        assert_eq!(items.len(), 2);
        assert_eq!(items[0].image, Path::new("/data/set/left/a.png"));
        assert_eq!(items[0].depth, Path::new("/data/set/depth/a.png"));
        assert_eq!(
            (items[0].sky_mask.as_ref(), items[0].camera.as_ref()),
            (None, None)
        );
        assert_eq!(items[0].out_dir, Path::new("left"));
        assert_eq!(items[0].stem, "a");
        assert_eq!(items[1].image, Path::new("/abs/b.jpg"));
        assert_eq!(items[1].out_dir, Path::new(""));
        assert_eq!(
            items[1].sky_mask.as_deref(),
            Some(Path::new("/data/set/masks/b.png"))
        );
    }

    /// Cells are CSV: a quoted path may hold a comma or quotes, as spreadsheets and pandas
    /// write it.
    #[test]
    fn manifest_cells_may_be_quoted() {
        let path = Path::new("/data/frames.csv");
        let text = "image,depth\n\"left/a, b.png\",\"d/\"\"q\"\".png\"\n";
        let items = parse_manifest(text, path).unwrap();
        assert_eq!(items[0].image, Path::new("/data/left/a, b.png"));
        assert_eq!(items[0].depth, Path::new("/data/d/\"q\".png"));
        assert_eq!(
            (items[0].out_dir.as_path(), items[0].stem.as_str()),
            (Path::new("left"), "a, b")
        );
    }

    /// The folder an image's outputs mirror does not depend on how the manifest's path was
    /// typed: an absolute image inside the manifest's folder mirrors its folder, one outside
    /// goes to the output root, with the manifest named relative to the working folder or
    /// not.
    #[test]
    fn manifest_folders_do_not_depend_on_how_its_path_is_typed() {
        let cwd = std::env::current_dir().unwrap();
        let inside = cwd.join("set/left/a.png");
        let text = format!(
            "image,depth\n{},d.png\n/elsewhere/b.png,d.png\n",
            inside.display()
        );
        for manifest in [Path::new("set/m.csv"), &cwd.join("set/m.csv")] {
            let items = parse_manifest(&text, manifest).unwrap();
            assert_eq!(items[0].out_dir, Path::new("left"), "{manifest:?}");
            assert_eq!(items[1].out_dir, Path::new(""), "{manifest:?}");
        }
        let items = parse_manifest("image,depth\n/elsewhere/b.png,d.png\n", Path::new("m.csv"));
        assert_eq!(items.unwrap()[0].out_dir, Path::new(""));
    }

    #[test]
    fn manifest_errors_name_the_file() {
        let path = Path::new("/data/frames.csv");
        let err = |text: &str| parse_manifest(text, path).unwrap_err().to_string();
        for (text, needle) in [
            ("", "empty manifest"),
            ("# only a comment\n\n", "empty manifest"),
            (
                "image,depth\n",
                "has a header but no rows: expected one row per frame",
            ),
            (
                "image,depth\n# a comment\n  \n",
                "has a header but no rows: expected one row per frame",
            ),
            ("image,depth,colour\na,b,c\n", "unknown column `colour`"),
            ("image,depth,image\na,b,c\n", "the column `image` twice"),
            ("depth,camera\na,b\n", "lacks the column `image`"),
            ("image,depth\na,b,c\n", "line 2: 3 cells, expected 2"),
            ("image,depth\n ,b\n", "line 2: the image cell is empty"),
            (
                "image,depth\na.png, \n",
                "line 2: no depth for /data/a.png: expected a depth file",
            ),
            (
                "image\na.exr\n",
                "only a phone's portrait JPEG carries its own",
            ),
        ] {
            let e = err(text);
            assert!(
                e.starts_with("/data/frames.csv: ") && e.contains(needle),
                "{text:?}: `{e}` should name the file and say `{needle}`"
            );
        }
    }

    /// A portrait JPEG without a depth cell, or in a manifest without the column, is its
    /// own depth file.
    #[test]
    fn a_portrait_jpeg_is_its_own_depth() {
        let path = Path::new("/data/frames.csv");
        let items = parse_manifest("image,depth\np/a.jpg,\nb.JPEG,d.png\n", path).unwrap();
        assert_eq!(items[0].depth, Path::new("/data/p/a.jpg"));
        assert_eq!(items[1].depth, Path::new("/data/d.png"));
        let items = parse_manifest("image\nIMG_1.jpg\n", path).unwrap();
        assert_eq!(items[0].depth, items[0].image);
    }

    #[test]
    fn read_manifest_reads_the_file_and_names_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.csv");
        std::fs::write(&path, "image,depth\ni.png,d.png\n").unwrap();
        let items = read_manifest(&path).unwrap();
        assert_eq!(items[0].depth, dir.path().join("d.png"));
        std::fs::write(&path, "image,depth\n").unwrap();
        let e = read_manifest(&path).unwrap_err().to_string();
        assert!(e.contains("m.csv") && e.contains("no rows"), "{e}");
        let e = read_manifest(&dir.path().join("none.csv")).unwrap_err();
        assert!(e.to_string().contains("none.csv"), "{e}");
    }

    #[test]
    fn swapping_the_layout_folder() {
        let p = Path::new("/c/leftImg8bit/train/aachen/a_leftImg8bit.png");
        assert_eq!(
            swap_component(p, "leftImg8bit", "disparity").unwrap(),
            Path::new("/c/disparity/train/aachen/a_leftImg8bit.png")
        );
        assert!(swap_component(Path::new("/c/x/a.png"), "leftImg8bit", "camera").is_none());
    }
}
