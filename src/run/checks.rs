//! Checks of option values made before any work: counts and times above zero, image sizes
//! the engine and the host can hold, and constants the graph has, of their type. The
//! messages describe the problem without naming the option: the command line puts its flag
//! in front, the Python module its keyword.

use lightgraph_engine::{ConstValue, Graph};
use std::time::Duration;

/// Constants the host sets from the image size and the samples per frame, never by hand.
const HOST_CONSTANTS: [&str; 5] = ["WIDTH", "HEIGHT", "PIXELS", "SAMPLES_PER_PIXEL", "PATHS"];

/// Bytes of host memory a pixel of a render holds: the film's f64 sums and sums of squares
/// (48), the GPU's f32 sums and sums of squares read back (with a spare word each, 32) and
/// the image made of them (f32 mean and variance, 48).
pub const HOST_BYTES_PER_PIXEL: u64 = 128;

/// Parses a count of at least 1 that fits `T` (a value parser for frames, samples, sizes).
pub fn count<T: TryFrom<u64>>(s: &str) -> Result<T, String> {
    let v: i128 = s
        .trim()
        .parse()
        .map_err(|_| "it must be a whole number of at least 1".to_string())?;
    if v < 1 {
        return Err("it must be at least 1".into());
    }
    u64::try_from(v)
        .ok()
        .and_then(|v| T::try_from(v).ok())
        .ok_or_else(|| "it is too large".to_string())
}

/// Parses a time above zero such as `500ms`, `10s`, `2m` or `1h`.
pub fn duration(s: &str) -> Result<Duration, String> {
    if s.trim_start().starts_with('-') {
        return Err("a time cannot be negative; give one above zero, e.g. 10s".into());
    }
    let d = humantime::parse_duration(s).map_err(|e| format!("it is not a time ({e}); e.g. 500ms, 10s, 2m, 1h"))?;
    if d.is_zero() {
        return Err("it must be longer than zero, e.g. 10s".into());
    }
    Ok(d)
}

/// Checks that a `width`×`height` image at `spp` samples per pixel a frame fits, before
/// anything is allocated: its paths a frame in the engine's 32-bit counts, and its film in the
/// host memory available now (MemAvailable of /proc/meminfo, where there is one).
pub fn image_fits(width: u32, height: u32, spp: u32) -> Result<(), String> {
    image_fits_in(width, height, spp, available_memory())
}

/// [`image_fits`] against `available` bytes of host memory (no check of memory when None).
pub fn image_fits_in(width: u32, height: u32, spp: u32, available: Option<u64>) -> Result<(), String> {
    let pixels = width as u64 * height as u64;
    let paths = pixels * spp as u64;
    if paths > u32::MAX as u64 {
        return Err(format!(
            "{paths} paths a frame, more than the engine's 32-bit counts hold ({})",
            u32::MAX
        ));
    }
    let needed = pixels * HOST_BYTES_PER_PIXEL;
    match available {
        Some(available) if needed > available => Err(format!(
            "the film needs {} of host memory ({HOST_BYTES_PER_PIXEL} bytes a pixel), more than the {} available",
            gib(needed),
            gib(available)
        )),
        _ => Ok(()),
    }
}

/// Bytes in GiB, with two decimals.
fn gib(bytes: u64) -> String {
    format!("{:.2} GiB", bytes as f64 / (1u64 << 30) as f64)
}

/// The host memory available to a new allocation, from /proc/meminfo (None elsewhere).
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The value `value` of constant `name` of `graph`, as the constant's type.
pub fn constant(graph: &Graph, name: &str, value: &str) -> Result<ConstValue, String> {
    if HOST_CONSTANTS.contains(&name) {
        return Err(format!(
            "{name} follows from the image size and the samples per frame; it cannot be set"
        ));
    }
    let declared = &graph.declared;
    let kind = match declared.constants.get(name) {
        Some(default) => *default,
        None if declared.derived.contains_key(name) => ConstValue::U32(0),
        None => return Err(unknown_constant(graph, name)),
    };
    let v = value.trim();
    let parsed = match kind {
        ConstValue::U32(_) => v.parse().ok().map(ConstValue::U32),
        ConstValue::I32(_) => v.parse().ok().map(ConstValue::I32),
        ConstValue::F32(_) => v.parse().ok().filter(|x: &f32| x.is_finite()).map(ConstValue::F32),
        ConstValue::Bool(_) => v.parse().ok().map(ConstValue::Bool),
    };
    parsed.ok_or_else(|| format!("{name} is {}, and '{value}' is not", type_words(kind)))
}

/// The type of a constant in words, with what its values look like.
fn type_words(kind: ConstValue) -> &'static str {
    match kind {
        ConstValue::U32(_) => "a u32 (a whole number from 0)",
        ConstValue::I32(_) => "an i32 (a whole number)",
        ConstValue::F32(_) => "an f32 (a finite number)",
        ConstValue::Bool(_) => "a bool (true or false)",
    }
}

/// Every constant a user may set in `graph`: declared and derived ones.
pub fn constant_names(graph: &Graph) -> Vec<&str> {
    let d = &graph.declared;
    let mut names: Vec<&str> = d.constants.keys().chain(d.derived.keys()).map(String::as_str).collect();
    names.sort_unstable();
    names.dedup();
    names
}

/// The error for a constant `graph` lacks: the names close to it, else all of them.
fn unknown_constant(graph: &Graph, name: &str) -> String {
    let names = constant_names(graph);
    let close: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| strsim::normalized_damerau_levenshtein(n, name) >= 0.6 || n.contains(name) || name.contains(n))
        .collect();
    match close.is_empty() {
        false => format!(
            "graph {} has no constant {name}; close names: {}",
            graph.name,
            close.join(", ")
        ),
        true => format!(
            "graph {} has no constant {name}; its constants: {}",
            graph.name,
            names.join(", ")
        ),
    }
}

/// An engine error of a buffer past the adapter's binding limit, said as what it is where the
/// buffer grows with the image (its count names PIXELS, WIDTH or HEIGHT): the image size is
/// too large, with the largest of its aspect that fits. Other errors are returned as they are.
pub fn image_past_binding_limit(error: anyhow::Error, graph: &Graph, (width, height): (u32, u32)) -> anyhow::Error {
    let text = format!("{error:#}");
    let grows = |count: &str| ["PIXELS", "WIDTH", "HEIGHT", "PATHS"].iter().any(|c| count.contains(c));
    let Some(resource) = graph
        .resources
        .iter()
        .find(|r| text.contains(&format!(" {} needs ", r.name)) && r.decl.count.as_deref().is_some_and(grows))
    else {
        return error;
    };
    let mib_after = |key: &str| -> Option<f64> {
        let rest = &text[text.find(key)? + key.len()..];
        rest[..rest.find(" MiB")?].trim().parse().ok()
    };
    let (Some(needed), Some(limit)) = (mib_after(" needs "), mib_after("binds at most ")) else {
        return error;
    };
    let count = resource.decl.count.as_deref().unwrap_or_default();
    // The largest image of this aspect whose buffer fits (a little below, for the rounding of
    // the MiB the engine reports).
    let scale = (limit / needed).sqrt() * 0.999;
    let fits = |side: u32| ((side as f64 * scale).floor() as u32).max(1);
    anyhow::anyhow!(
        "the image size (--res) {width}x{height} is too large for this adapter: the graph's buffer '{}' ({} \
         elements of {}) needs {needed:.1} MiB, more than the {limit:.1} MiB the adapter binds in one buffer \
         (its max_storage_buffer_binding_size); give a smaller --res, at most about {}x{} at this aspect{}",
        resource.name,
        count,
        resource.decl.ty,
        fits(width),
        fits(height),
        match count.contains("PATHS") {
            true => " and --spp (or a smaller --spp: the buffer holds an element a sample)",
            false => "",
        }
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_below_one_and_out_of_range_are_refused() {
        assert_eq!(count::<u32>("3"), Ok(3));
        assert!(count::<u32>("0").unwrap_err().contains("at least 1"));
        assert!(count::<u32>("-2").unwrap_err().contains("at least 1"));
        assert!(count::<u32>("x").unwrap_err().contains("whole number"));
        assert!(count::<u32>("4294967296").unwrap_err().contains("too large"));
        assert_eq!(count::<u64>("4294967296"), Ok(4294967296));
    }

    #[test]
    fn times_must_be_above_zero() {
        assert_eq!(duration("1500ms"), Ok(Duration::from_millis(1500)));
        assert!(duration("0s").unwrap_err().contains("longer than zero"));
        assert!(duration("-1s").unwrap_err().contains("negative"));
        assert!(duration("soon").unwrap_err().contains("not a time"));
    }

    #[test]
    fn an_image_must_fit_the_counts_and_the_memory() {
        assert_eq!(image_fits_in(1920, 1080, 16, Some(1 << 30)), Ok(()));
        let paths = image_fits_in(100_000, 100_000, 1, None).unwrap_err();
        assert!(
            paths.contains("10000000000 paths") && paths.contains("4294967295"),
            "{paths}"
        );
        let spp = image_fits_in(256, 256, 100_000, None).unwrap_err();
        assert!(spp.contains("6553600000 paths"), "{spp}");
        // 1024 x 1024 pixels at 128 bytes: 128 MiB, against 64 MiB available.
        let memory = image_fits_in(1024, 1024, 1, Some(64 << 20)).unwrap_err();
        assert!(
            memory.contains("0.12 GiB") && memory.contains("0.06 GiB available"),
            "{memory}"
        );
        assert_eq!(image_fits_in(1024, 1024, 1, Some(256 << 20)), Ok(()));
    }
}
