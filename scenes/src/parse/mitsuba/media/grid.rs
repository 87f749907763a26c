//! Heterogeneous media: Mitsuba 3's `heterogeneous` medium whose extinction `sigma_t` is a
//! `gridvolume` (a `.vol` file of one channel, `filter_type`, `to_world`, `use_grid_bbox`),
//! with a constant `albedo` (default 0.75), `scale` and phase function (docs/media.md).

use super::super::transform;
use super::super::xml::{Context, Props, Result};
use super::{constant, scale_and_phase};
use crate::model::grid::{DensityGrid, GridFilter, VolumeGrid};
use crate::model::media::{Medium, check_medium};
use glam::Mat4;
use roxmltree::Node;
use std::sync::Arc;

/// A `<medium type="heterogeneous">` element as a [`Medium`] with a density grid.
pub fn heterogeneous<'a, 'i>(ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<Medium> {
    let props = Props::new(node);
    let Some(sigma_t) = props.get("sigma_t") else {
        return Err(ctx.error(node, "a heterogeneous medium needs a sigma_t gridvolume"));
    };
    let volume = ctx.resolve(sigma_t)?;
    if !volume.has_tag_name("volume") {
        return Err(ctx.error(
            volume,
            "sigma_t of a heterogeneous medium must be a gridvolume (a constant: use a homogeneous medium)",
        ));
    }
    let grid = gridvolume(ctx, volume)?;
    let albedo = match constant(ctx, &props, "albedo")? {
        None => [0.75; 3],
        Some((at, value)) if value.iter().any(|c| !(0.0..=1.0).contains(c)) => {
            return Err(ctx.error(at, format!("the albedo {value:?} is not within [0, 1]")));
        }
        Some((_, value)) => value,
    };
    let (scale, phase) = scale_and_phase(ctx, node, &props)?;
    let m = Medium {
        sigma_a: albedo.map(|a| 1.0 - a),
        sigma_s: albedo,
        scale,
        phase,
        grid: Some(grid),
    };
    check_medium(&m).map_err(|e| ctx.error(node, e))?;
    props.finish(ctx);
    Ok(m)
}

/// A `<volume type="gridvolume">` of one channel, read from its `.vol` file.
fn gridvolume<'a, 'i>(ctx: &mut Context<'a, 'i>, node: Node<'a, 'i>) -> Result<DensityGrid> {
    let kind = ctx.plugin_type(node)?;
    if kind != "gridvolume" && kind != "grid" {
        return Err(ctx.error(
            node,
            format!("the volume type '{kind}' is not supported: only gridvolume"),
        ));
    }
    let props = Props::new(node);
    let path = props.file(ctx, "a gridvolume")?;
    let at = props.get("filename").unwrap_or(node);
    let volume = std::fs::read(&path)
        .map_err(|e| e.to_string())
        .and_then(|bytes| VolumeGrid::from_vol(&bytes))
        .map_err(|e| ctx.error(at, format!("{}: {e}", path.display())))?;
    let filter = match props.string(ctx, "filter_type")?.as_deref() {
        None | Some("trilinear") => GridFilter::Trilinear,
        Some("nearest") => GridFilter::Nearest,
        Some(other) => {
            return Err(ctx.error(
                props.get("filter_type").unwrap_or(node),
                format!("filter_type '{other}' is neither trilinear nor nearest"),
            ));
        }
    };
    if let Some(mode) = props.string(ctx, "wrap_mode")?.filter(|m| m != "clamp") {
        return Err(ctx.error(
            props.get("wrap_mode").unwrap_or(node),
            format!("wrap_mode '{mode}' is not supported: only clamp (the default)"),
        ));
    }
    let mut to_world = transform::to_world(ctx, &props)?;
    if props.boolean(ctx, "use_grid_bbox")?.unwrap_or(false) {
        let [lo, hi] = volume.bbox.map(glam::Vec3::from);
        to_world *= Mat4::from_translation(lo) * Mat4::from_scale(hi - lo);
    }
    for harmless in ["raw", "accel"] {
        props.get(harmless);
    }
    props.finish(ctx);
    Ok(DensityGrid {
        file: path.display().to_string(),
        to_world: std::array::from_fn(|r| to_world.row(r).to_array()),
        filter,
        volume: Some(Arc::new(volume)),
    })
}

#[cfg(test)]
mod tests {
    use super::super::super::parse;
    use crate::model::grid::tests::vol_bytes;
    use crate::model::grid::{GridFilter, identity};
    use std::path::PathBuf;

    /// A folder of its own for test `name`, holding `cloud.vol`: a 2 x 2 x 2 grid of
    /// densities 0 to 7 with the box (0, 0, 0)-(1, 2, 3).
    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("lightgraph-grid-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let data: Vec<f32> = (0..8).map(|i| i as f32).collect();
        std::fs::write(dir.join("cloud.vol"), vol_bytes([2, 2, 2], &data)).unwrap();
        dir
    }

    /// Imports a scene of a cube holding `medium` from `dir`: the medium, or the error.
    fn import(dir: &std::path::Path, medium: &str) -> Result<crate::model::media::Medium, String> {
        let text = format!(
            "<scene version=\"3.0.0\">\n<shape type=\"cube\"><bsdf type=\"null\"/>\n{medium}</shape>\n<emitter type=\"constant\"/></scene>"
        );
        let imported = parse("t.xml", dir, &text).map_err(|e| e.to_string())?;
        Ok(imported.scene.media.into_values().next().expect("one medium"))
    }

    #[test]
    fn a_heterogeneous_medium_reads_its_gridvolume() {
        let dir = folder("read");
        let m = import(
            &dir,
            "<medium type=\"heterogeneous\" name=\"interior\"><volume type=\"gridvolume\" name=\"sigma_t\">\
             <string name=\"filename\" value=\"cloud.vol\"/><string name=\"filter_type\" value=\"nearest\"/>\
             <transform name=\"to_world\"><translate x=\"1\"/></transform></volume>\
             <rgb name=\"albedo\" value=\"0.9, 0.5, 0.25\"/><float name=\"scale\" value=\"4\"/></medium>",
        )
        .unwrap();
        let albedo = [0.9, 0.5, 0.25];
        assert_eq!((m.sigma_s, m.sigma_a, m.scale), (albedo, albedo.map(|a| 1.0 - a), 4.0));
        let grid = m.grid.unwrap();
        assert_eq!(grid.filter, GridFilter::Nearest);
        let mut moved = identity();
        moved[0][3] = 1.0;
        assert_eq!(grid.to_world, moved);
        assert_eq!(grid.volume.unwrap().data[7], 7.0);
        // use_grid_bbox: the unit cube goes to the file's box (0, 0, 0)-(1, 2, 3) first.
        let m = import(
            &dir,
            "<medium type=\"heterogeneous\" name=\"interior\"><volume type=\"gridvolume\" name=\"sigma_t\">\
             <string name=\"filename\" value=\"cloud.vol\"/><boolean name=\"use_grid_bbox\" value=\"true\"/></volume></medium>",
        )
        .unwrap();
        let to_world = m.grid.unwrap().to_world;
        assert_eq!((to_world[0][0], to_world[1][1], to_world[2][2]), (1.0, 2.0, 3.0));
        assert_eq!(m.sigma_s, [0.75; 3]);
    }

    #[test]
    fn bad_heterogeneous_media_are_errors_naming_the_file_and_element() {
        let dir = folder("errors");
        std::fs::write(
            dir.join("bad.vol"),
            b"VOX\x03 and more bytes than a header has, surely more than 48",
        )
        .unwrap();
        let grid = |props: &str| {
            format!(
                "<medium type=\"heterogeneous\" name=\"interior\">\n<volume type=\"gridvolume\" name=\"sigma_t\">\n{props}</volume></medium>"
            )
        };
        let cases = [
            (
                grid("<string name=\"filename\" value=\"bad.vol\"/>"),
                format!(
                    "t.xml:5:1: <string name=\"filename\">: {}: not a .vol file",
                    dir.join("bad.vol").display()
                ),
            ),
            (
                grid("<string name=\"filename\" value=\"none.vol\"/>"),
                "the file".to_string() + &format!(" '{}' does not exist", dir.join("none.vol").display()),
            ),
            (
                grid("<string name=\"filename\" value=\"cloud.vol\"/><string name=\"wrap_mode\" value=\"repeat\"/>"),
                "wrap_mode 'repeat' is not supported".into(),
            ),
            (
                grid("<string name=\"filename\" value=\"cloud.vol\"/><string name=\"filter_type\" value=\"cubic\"/>"),
                "filter_type 'cubic' is neither trilinear nor nearest".into(),
            ),
            (
                "<medium type=\"heterogeneous\" name=\"interior\"><float name=\"sigma_t\" value=\"1\"/></medium>".into(),
                "sigma_t of a heterogeneous medium must be a gridvolume".into(),
            ),
            (
                grid("<string name=\"filename\" value=\"cloud.vol\"/><transform name=\"to_world\"><scale x=\"0\"/></transform>")
                    .replace("</medium>", "<float name=\"scale\" value=\"2\"/></medium>"),
                "is not an invertible, finite map".into(),
            ),
        ];
        for (medium, expected) in cases {
            let e = import(&dir, &medium).expect_err("refused");
            assert!(e.contains(&expected), "{medium}:\n{e}\nlacks\n{expected}");
        }
    }
}
