//! Datasets of RGBD frames to fog in bulk (`brume batch`): Cityscapes triplets found under
//! folders, or the rows of a CSV manifest; deterministic shards for array jobs; Foggy
//! Cityscapes' output names.

use crate::error::{Error, Result};
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

    /// Parses `K/N` with 1 ≤ K ≤ N.
    pub fn parse(text: &str) -> Result<Self> {
        let bad = || {
            Error::invalid(
                "--shard",
                text,
                "K/N with 1 ≤ K ≤ N (e.g. 3/8; Slurm: $((SLURM_ARRAY_TASK_ID+1))/$SLURM_ARRAY_TASK_COUNT)",
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
    pub fn contains(&self, item: &Item) -> bool {
        fnv1a(item.key().as_bytes()) % u64::from(self.count) == u64::from(self.index - 1)
    }
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
    walk(root, &mut images)?;
    images.sort();
    Ok(images
        .iter()
        .map(|image| cityscapes_item(root, image))
        .collect())
}

/// Collects the Cityscapes left images under `dir`, recursively.
fn walk(dir: &Path, images: &mut Vec<PathBuf>) -> Result<()> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let kind = entry.file_type().map_err(|e| Error::io(&path, e))?;
        if kind.is_dir() {
            walk(&path, images)?;
        } else if path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().ends_with(CITYSCAPES_IMAGE_SUFFIX))
        {
            images.push(path);
        }
    }
    Ok(())
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

/// The frames of a CSV manifest: a header naming the columns `image` and `depth`
/// (required) and `camera`, `calib`, `sky_mask` (optional; empty cells allowed), then one
/// row per frame. Relative paths are relative to the manifest's folder; outputs mirror
/// the images' folders relative to it.
pub fn read_manifest(path: &Path) -> Result<Vec<Item>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let (_, header) = lines.next().ok_or_else(|| Error::Format {
        path: path.to_path_buf(),
        detail: "empty manifest: expected a header `image,depth[,camera][,calib][,sky_mask]`"
            .into(),
    })?;
    let columns: Vec<String> = header.split(',').map(|c| c.trim().to_lowercase()).collect();
    let column = |name: &str| columns.iter().position(|c| c == name);
    for c in &columns {
        if !["image", "depth", "camera", "calib", "sky_mask"].contains(&c.as_str()) {
            return Err(Error::Format {
                path: path.to_path_buf(),
                detail: format!(
                    "unknown column `{c}`: expected image, depth, camera, calib, sky_mask"
                ),
            });
        }
    }
    let (Some(image_col), Some(depth_col)) = (column("image"), column("depth")) else {
        return Err(Error::Format {
            path: path.to_path_buf(),
            detail: format!("the header `{header}` lacks the column `image` or `depth`"),
        });
    };
    let mut items = Vec::new();
    for (n, line) in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != columns.len() {
            return Err(Error::Format {
                path: path.to_path_buf(),
                detail: format!(
                    "line {}: {} cells, expected {} (as the header)",
                    n + 1,
                    cells.len(),
                    columns.len()
                ),
            });
        }
        let cell = |i: Option<usize>| {
            i.map(|i| cells[i])
                .filter(|c| !c.is_empty())
                .map(|c| base.join(c))
        };
        let (Some(image), Some(depth)) = (cell(Some(image_col)), cell(Some(depth_col))) else {
            return Err(Error::Format {
                path: path.to_path_buf(),
                detail: format!("line {}: the image or depth cell is empty", n + 1),
            });
        };
        let out_dir = image
            .parent()
            .and_then(|p| p.strip_prefix(base).ok())
            .map(Path::to_path_buf)
            .unwrap_or_default();
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
    Ok(items)
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

    #[test]
    fn shard_syntax() {
        assert_eq!(Shard::parse("3/8").unwrap(), Shard { index: 3, count: 8 });
        for bad in ["0/4", "5/4", "3", "a/b", "1/0", "-1/4", ""] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--shard") && e.contains("K/N"), "{bad}: {e}");
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
    fn swapping_the_layout_folder() {
        let p = Path::new("/c/leftImg8bit/train/aachen/a_leftImg8bit.png");
        assert_eq!(
            swap_component(p, "leftImg8bit", "disparity").unwrap(),
            Path::new("/c/disparity/train/aachen/a_leftImg8bit.png")
        );
        assert!(swap_component(Path::new("/c/x/a.png"), "leftImg8bit", "camera").is_none());
    }
}
