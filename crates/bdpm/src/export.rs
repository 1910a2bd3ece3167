//! `bdpm export`: a scene as another renderer's scene (Mitsuba 3 XML with PLY meshes), so
//! that it can render the same triangles, camera, lights and materials
//! (docs/scene-format.md, "Export to Mitsuba 3").
use std::path::{Path, PathBuf};

use bdpm_integrator::Setting;
use bdpm_output::cli::{CliResult, Overrides, count, parse_resolution, prepare};
use bdpm_output::{say, say_err};
use clap::{Args, ValueEnum};

/// The formats `export` writes.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Format {
    /// Mitsuba 3: DIR/scene.xml (scene format 3.0.0), DIR/meshes/*.ply, DIR/textures/*.exr,
    /// DIR/export.json.
    Mitsuba,
}

#[derive(Args, Debug)]
pub(crate) struct ExportArgs {
    /// Scene file (TOML; its glTF, OBJ and PLY meshes are exported as loaded).
    scene: PathBuf,
    /// The format to write.
    #[arg(long = "to", value_enum)]
    to: Format,
    /// Output directory (created if missing; the files are written as a set).
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Image size as WxH (default: the scene file's).
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Camera samples per pixel per pass: with --passes, the sampler's default sample count
    /// spp × passes (Mitsuba's `$spp`).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::Spp))]
    spp: Option<u32>,
    /// Passes (see --spp).
    #[arg(long, allow_negative_numbers = true, value_parser = count::<u32>(Setting::Passes))]
    passes: Option<u32>,
    /// Print nothing but errors and warnings.
    #[arg(long)]
    quiet: bool,
}

pub(crate) fn run(args: ExportArgs) -> CliResult<()> {
    let Format::Mitsuba = args.to;
    let overrides = Overrides {
        resolution: args.resolution,
        spp: args.spp,
        passes: args.passes,
        ..Overrides::default()
    };
    let loaded = prepare(&args.scene, &overrides)?;
    for warning in loaded.report.warnings() {
        say_err!("warning: {warning}");
    }
    let export = bdpm_export::mitsuba(&loaded.scene, &loaded.settings, &args.scene)
        .map_err(|e| e.to_string())?;
    let members: Vec<PathBuf> = export
        .files
        .iter()
        .map(|f| args.output.join(&f.path))
        .collect();
    let mut inputs: Vec<&Path> = vec![&args.scene];
    inputs.extend(loaded.report.gltf_files.iter().map(PathBuf::as_path));
    let member_refs: Vec<&Path> = members.iter().map(PathBuf::as_path).collect();
    bdpm_output::files::refuse_inputs(&member_refs, &inputs, &[])?;
    for warning in &export.report.warnings {
        say_err!("warning: {warning}");
    }
    bdpm_export::write(&export, &args.output).map_err(|e| e.to_string())?;
    if !args.quiet {
        let r = &export.report;
        say!(
            "wrote {}: {} shapes ({} triangles), {} bsdfs, {} emitters, {} textures, {} warnings \
             (report: {})",
            args.output.join(bdpm_export::SCENE_FILE).display(),
            r.shapes,
            r.triangles,
            r.bsdfs,
            r.emitters,
            r.textures,
            r.warnings.len(),
            args.output.join(bdpm_export::REPORT_FILE).display()
        );
    }
    Ok(())
}
