//! The settings a batch's outputs were made with, kept beside them in
//! [`SETTINGS_FILE`]. A run skips the outputs already written; had they been made with
//! other settings (another λ, albedo, airlight, noise…), it would leave a dataset of two
//! kinds of fog under one name, so such a run is refused before any work.

use super::batch::{BatchOptions, Betas};
use crate::error::{Error, Result};
use crate::io::output;
use serde_json::{json, Value};
use std::path::Path;

/// The file in a batch's output folder that records its settings: `{"brume": version,
/// "sources": fingerprint, "settings": {...}}` ([`crate::VERSION`], [`crate::SOURCES`]),
/// the settings as [`settings_of`] gives them.
pub const SETTINGS_FILE: &str = "brume-batch-settings.json";

/// The most differences an error lists.
const SHOWN_DIFFERENCES: usize = 6;

/// The longest value an error shows of a setting.
const SHOWN_VALUE_CHARS: usize = 60;

/// The settings that decide a batch's outputs, as JSON: how every frame is read,
/// prepared and fogged (`frame`, the files it names as full paths), the camera after the
/// fog (`capture`, its seed only where it draws noise or β) and the distribution β is
/// drawn from (`beta_dist`). Not the β list, each β's outputs having names of their own,
/// nor the shard, the threads or the τ maps, which decide what is written, not how.
pub fn settings_of(opts: &BatchOptions) -> Value {
    let mut frame = opts.frame.clone();
    let paths = [
        &mut frame.depth.calib,
        &mut frame.depth.camera,
        &mut frame.sky_mask,
        &mut frame.ego_mask,
    ];
    for path in paths.into_iter().flatten() {
        // The same file named from another folder is the same setting.
        if let Ok(full) = std::fs::canonicalize(&*path) {
            *path = full;
        }
    }
    let mut frame = to_value(&frame);
    if let Some(fog) = frame["fog"].as_object_mut() {
        // Each β's own extinction replaces it.
        fog.remove("extinction");
    }
    let beta_dist = match &opts.betas {
        Betas::Drawn(dist) => Some(dist.to_string()),
        Betas::Each(_) => None,
    };
    let mut capture = to_value(&opts.capture);
    if opts.capture.is_off() && beta_dist.is_none() {
        if let Some(capture) = capture.as_object_mut() {
            capture.remove("seed");
        }
    }
    json!({ "frame": frame, "capture": capture, "beta_dist": beta_dist })
}

/// `value` as JSON, through its text: `serde_json::to_value` widens an `f32` to the `f64`
/// nearest (an airlight of 0.9 becomes 0.8999999761581421), where the text has its
/// shortest form.
fn to_value(value: &impl serde::Serialize) -> Value {
    let text = serde_json::to_string(value).expect("options serialise");
    serde_json::from_str(&text).expect("serde_json reads what it writes")
}

/// Refuses `out` when its [`SETTINGS_FILE`] records other settings than `settings`, naming
/// those that differ; warns when they were recorded by another version or build of brume.
/// A folder without the file (new, or filled by a brume before it) passes.
pub(super) fn check_settings(out: &Path, settings: &Value) -> Result<()> {
    let path = out.join(SETTINGS_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(&path, e)),
    };
    let not_a_record = |why: String| {
        Error::format(
            &path,
            format!(
                "not brume's record of a batch's settings ({why}); remove it if the folder's \
                 outputs were made with these settings"
            ),
        )
    };
    let recorded: Value = serde_json::from_str(&text).map_err(|e| not_a_record(e.to_string()))?;
    if !recorded["settings"].is_object() {
        return Err(not_a_record("no \"settings\" object".into()));
    }
    let mut differences = Vec::new();
    let defaults = settings_of(&BatchOptions::new(out.to_path_buf()));
    differ(
        &recorded["settings"],
        settings,
        &defaults,
        "",
        &mut differences,
    );
    if differences.is_empty() {
        if let Some(other) = other_build(&recorded) {
            log::warn!(
                "{}'s outputs were made by {other} with these settings: where brume changed \
                 since, its new outputs may differ from the old",
                out.display(),
            );
        }
        return Ok(());
    }
    let more = differences.len().saturating_sub(SHOWN_DIFFERENCES);
    differences.truncate(SHOWN_DIFFERENCES);
    if more > 0 {
        differences.push(format!("{more} more"));
    }
    Err(Error::invalid(
        "out",
        out.display(),
        format!(
            "a new folder or one of outputs made with these settings: {} records other \
             settings for its outputs ({}), and adding to them would put two kinds of fog \
             in one dataset. Give another `out` or the same settings; or remove that file \
             to add outputs made with these settings anyway",
            path.display(),
            differences.join("; ")
        ),
    ))
}

/// The build of brume that made `recorded`, as a warning names it with this one, when it
/// is not this one: another version, or the same version from other sources (a record
/// without a fingerprint was made before brume kept one, by an older build).
fn other_build(recorded: &Value) -> Option<String> {
    let version = recorded["brume"].as_str().unwrap_or("unknown");
    let sources = recorded["sources"].as_str();
    if version != crate::VERSION {
        Some(format!("brume {version} (this is {})", crate::VERSION))
    } else if sources != Some(crate::SOURCES) {
        Some(format!(
            "another build of brume {version} (sources {}; this is {})",
            sources.unwrap_or("not recorded"),
            crate::SOURCES
        ))
    } else {
        None
    }
}

/// Records `settings` in `out`'s [`SETTINGS_FILE`] if it has none, atomically; where
/// another run (a shard started at the same time) recorded its own first, checks them as
/// [`check_settings`] does.
pub(super) fn record_settings(out: &Path, settings: &Value) -> Result<()> {
    let path = out.join(SETTINGS_FILE);
    if path.exists() {
        return check_settings(out, settings);
    }
    let record = json!({
        "brume": crate::VERSION,
        "sources": crate::SOURCES,
        "settings": settings
    });
    let mut text = serde_json::to_string_pretty(&record).expect("JSON values serialise");
    text.push('\n');
    if output::write_bytes_unless_present(&path, text.as_bytes())? {
        Ok(())
    } else {
        check_settings(out, settings)
    }
}

/// Appends to `differences` each setting under `path` whose value differs between `old`
/// and `new`, as `path old there, new here`; objects are compared key by key. A setting
/// `old` lacks (the brume that recorded it had no such option) counts as its value in
/// `defaults`; one `new` lacks (an option this brume no longer has) is passed over.
fn differ(old: &Value, new: &Value, defaults: &Value, path: &str, differences: &mut Vec<String>) {
    if let (Value::Object(o), Value::Object(n)) = (old, new) {
        for (key, n) in n {
            let inner = match path {
                "" => key.clone(),
                _ => format!("{path}.{key}"),
            };
            let default = defaults.get(key).unwrap_or(&Value::Null);
            differ(
                o.get(key).unwrap_or(default),
                n,
                default,
                &inner,
                differences,
            );
        }
    } else if old != new {
        // The frame's settings are most of them: named without their prefix.
        let name = path.strip_prefix("frame.").unwrap_or(path);
        differences.push(format!("{name} {} there, {} here", shown(old), shown(new)));
    }
}

/// A setting's value as an error shows it: compact JSON, cut short.
fn shown(value: &Value) -> String {
    let text = match value {
        Value::Null => "none".to_string(),
        other => other.to_string(),
    };
    match text.char_indices().nth(SHOWN_VALUE_CHARS) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::{BetaDistribution, SensorNoise};

    fn options(out: &Path) -> BatchOptions {
        BatchOptions::new(out.to_path_buf())
    }

    #[test]
    fn other_settings_are_refused_naming_each_difference() {
        let dir = tempfile::tempdir().unwrap();
        let first = options(dir.path());
        record_settings(dir.path(), &settings_of(&first)).unwrap();
        let recorded = std::fs::read(dir.path().join(SETTINGS_FILE)).unwrap();

        let mut other = first.clone();
        other.frame.fog.lambda = 3.5;
        other.frame.prepare.prep.as_mut().unwrap().margin_px = 12.0;
        other.capture.noise = Some(SensorNoise {
            gain: 0.0,
            read_noise: 0.01,
        });
        let e = check_settings(dir.path(), &settings_of(&other))
            .unwrap_err()
            .to_string();
        for difference in [
            "fog.lambda 8.0 there, 3.5 here",
            "prepare.prep.margin_px 8.0 there, 12.0 here",
            r#"capture.noise none there, {"gain":0.0,"read_noise":0.01} here"#,
        ] {
            assert!(e.contains(difference), "{difference}: {e}");
        }
        assert!(e.contains("`out`") && e.contains(SETTINGS_FILE), "{e}");
        // Recording them anyway checks them, and leaves the record as it was.
        assert!(record_settings(dir.path(), &settings_of(&other)).is_err());
        assert!(record_settings(dir.path(), &settings_of(&first)).is_ok());
        assert_eq!(
            std::fs::read(dir.path().join(SETTINGS_FILE)).unwrap(),
            recorded
        );
    }

    #[test]
    fn what_does_not_decide_the_pixels_is_no_setting() {
        let dir = tempfile::tempdir().unwrap();
        let first = options(dir.path());
        let mut other = first.clone();
        other.betas = Betas::Each(vec![0.03, 0.04]);
        other.transmittance = true;
        other.loaders = 3;
        other.writers = 2;
        other.capture.seed = 7;
        other.frame.fog.extinction = crate::photo::Extinction::Normalised { ka: 1.0, ks: 2.0 };
        assert_eq!(settings_of(&first), settings_of(&other));
        // The seed draws a drawn β and the noise: then it counts.
        let drawn = |seed| {
            let mut o = first.clone();
            o.betas = Betas::Drawn(BetaDistribution::Uniform {
                low: 0.01,
                high: 0.02,
            });
            o.capture.seed = seed;
            settings_of(&o)
        };
        assert_ne!(drawn(1), drawn(2));
    }

    #[test]
    fn a_file_named_from_elsewhere_is_the_same_setting() {
        let dir = tempfile::tempdir().unwrap();
        let mut relative = options(dir.path());
        relative.frame.depth.camera = Some("Cargo.toml".into());
        let mut absolute = relative.clone();
        absolute.frame.depth.camera =
            Some(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.toml"));
        assert_eq!(settings_of(&relative), settings_of(&absolute));
        absolute.frame.depth.camera = Some("README.md".into());
        assert_ne!(settings_of(&relative), settings_of(&absolute));
    }

    #[test]
    fn an_airlight_is_recorded_as_given() {
        let mut opts = options(Path::new("out"));
        opts.frame.prepare.airlight = Some([0.9, 0.8, 0.7]);
        let settings = settings_of(&opts);
        assert_eq!(
            settings["frame"]["prepare"]["airlight"].to_string(),
            "[0.9,0.8,0.7]"
        );
    }

    #[test]
    fn another_version_passes_and_a_broken_record_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let settings = settings_of(&options(dir.path()));
        let path = dir.path().join(SETTINGS_FILE);
        let old = json!({ "brume": "0.0.1", "settings": settings });
        std::fs::write(&path, old.to_string()).unwrap();
        check_settings(dir.path(), &settings).unwrap();
        for broken in ["{\"brume\": ", "{\"brume\": \"0.1.0\"}", "[1]"] {
            std::fs::write(&path, broken).unwrap();
            let e = check_settings(dir.path(), &settings)
                .unwrap_err()
                .to_string();
            assert!(e.contains(SETTINGS_FILE) && e.contains("remove it"), "{e}");
        }
    }

    /// Outputs made by another build of this version (a clone's earlier commit) are told
    /// apart by their sources' fingerprint.
    #[test]
    fn another_build_of_this_version_is_named() {
        let record = |version: &str, sources: Option<&str>| json!({ "brume": version, "sources": sources, "settings": {} });
        assert_eq!(
            other_build(&record(crate::VERSION, Some(crate::SOURCES))),
            None
        );
        let other = other_build(&record(crate::VERSION, Some("0123456789abcdef"))).unwrap();
        assert!(
            other.contains("another build") && other.contains("0123456789abcdef"),
            "{other}"
        );
        assert!(other.contains(crate::SOURCES), "{other}");
        let unrecorded = other_build(&record(crate::VERSION, None)).unwrap();
        assert!(unrecorded.contains("not recorded"), "{unrecorded}");
        let older = other_build(&record("0.0.1", Some(crate::SOURCES))).unwrap();
        assert!(older.contains("brume 0.0.1 (this is"), "{older}");
        assert_eq!(crate::SOURCES.len(), 16);
        assert!(crate::SOURCES.bytes().all(|b| b.is_ascii_hexdigit()));
    }

    /// A record by a brume that lacked an option counts it as its default; an option
    /// this brume no longer has is passed over.
    #[test]
    fn an_option_the_record_lacks_counts_as_its_default() {
        let dir = tempfile::tempdir().unwrap();
        let current = options(dir.path());
        let mut older = settings_of(&current);
        let prep = older["frame"]["prepare"]["prep"].as_object_mut().unwrap();
        prep.remove("border_band_fraction").unwrap();
        prep.insert("retired_option".into(), json!(3));
        let record = json!({ "brume": "0.0.1", "settings": older });
        std::fs::write(dir.path().join(SETTINGS_FILE), record.to_string()).unwrap();
        check_settings(dir.path(), &settings_of(&current)).unwrap();
        let mut changed = current.clone();
        changed
            .frame
            .prepare
            .prep
            .as_mut()
            .unwrap()
            .border_band_fraction = 0.3;
        let e = check_settings(dir.path(), &settings_of(&changed))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("prepare.prep.border_band_fraction 0.15 there, 0.3 here"),
            "{e}"
        );
    }
}
