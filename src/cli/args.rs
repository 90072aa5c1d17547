//! The command line's arguments (clap).

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use glint::scene::TriangleAlgorithm;

/// `glint`'s arguments.
#[derive(Parser)]
#[command(
    name = "glint",
    version,
    about = "A WGSL compute-shader ray tracer with a bit-exact CPU mirror"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// CPU threads for the CPU tracers, the BVH build and the mesh readers (default: one
    /// per core).
    #[arg(long, global = true, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub threads: Option<u32>,
}

/// The options every subcommand that loads a scene shares.
#[derive(clap::Args)]
pub struct CommonArgs {
    /// Use the first Vulkan adapter whose name contains this.
    #[arg(long)]
    pub adapter: Option<String>,
    /// Read only files below the scene's own folder (meshes, MTLs; links followed).
    #[arg(long)]
    pub confine: bool,
    /// Change a key of the scene before it is read: a dotted TOML path and a TOML value
    /// (camera.fov=30, lights[0].color=[1,0,0], output.encoding=srgb; a word is a string).
    /// Repeatable; applied in order.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<glint::scene::set::Setting>,
}

/// The frame options of `render` and `compare`.
#[derive(clap::Args)]
pub struct FrameArgs {
    /// Image size WxH (default: the scene's camera).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// Triangle algorithm (default: the scene's).
    #[arg(long)]
    pub triangle: Option<TriangleAlgorithm>,
    /// Antialiasing: N×N samples a pixel (default: the scene camera's `samples`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=glint::scene::MAX_SAMPLES as i64))]
    pub samples: Option<u32>,
    /// The most reflections plus refractions along a path (default: the scene's
    /// `max_depth`; 0: local shading only).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=glint::scene::MAX_DEPTH as i64))]
    pub max_depth: Option<u32>,
    /// The GPU kernel's division and square root: exact (correctly rounded on every
    /// Vulkan driver: the GPU image is the CPU mirror's) or fast (the driver's own).
    #[arg(long, value_enum, default_value = "exact")]
    pub math: MathArg,
    /// Make the GPU driver's `/` and `sqrt` deliberately inexact (up to ±2 ULP, varying
    /// from operation to operation and pixel to pixel): with --math exact the image must
    /// not change; a proof of exactness on a driver that is exact already (lavapipe).
    #[arg(long)]
    pub inexact_driver: bool,
    /// AOVs beside the colour, comma-separated: t, depth, position, geo_normal, normal,
    /// albedo, prim_id, object_id, material_id, mask (docs/aov.md). An EXR holds them as
    /// channels (`depth`, `normal.X`, ...); a PNG gets a PNG for each beside it
    /// (OUT.normal.png). `compare` compares the GPU's with the mirror's, bit for bit.
    #[arg(long, value_name = "LIST", value_parser = parse_aovs)]
    pub aov: Option<AovList>,
}

/// `--aov`'s list, in [`glint::render::Aov::ALL`]'s order.
#[derive(Clone, Debug)]
pub struct AovList(pub Vec<glint::render::Aov>);

fn parse_aovs(s: &str) -> Result<AovList, String> {
    glint::render::Aov::parse_list(s)
        .map(AovList)
        .map_err(|e| e.to_string())
}

/// `--math`: glint's [`glint::buffers::Math`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MathArg {
    /// Correctly rounded division and square root on every driver (the driver's own
    /// where they are correctly rounded already: lavapipe).
    Exact,
    /// The corrections even where the driver rounds correctly (the same bits; their cost).
    Corrected,
    /// The driver's own division and square root.
    Fast,
}

impl From<MathArg> for glint::buffers::Math {
    fn from(m: MathArg) -> Self {
        match m {
            MathArg::Exact => glint::buffers::Math::Exact,
            MathArg::Corrected => glint::buffers::Math::Corrected,
            MathArg::Fast => glint::buffers::Math::Fast,
        }
    }
}

/// The subcommands.
#[derive(Subcommand)]
pub enum Command {
    /// Render a scene to a PNG (or an EXR).
    Render {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output image: .png (8-bit) or .exr (the f32 image exactly, t in alpha); default:
        /// the scene's name with .png, in the current folder (scenes/bb8.toml → bb8.png).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Print the time of each stage (read, gunzip, parse, BVH build, trace, PNG, ...).
        #[arg(short, long, conflicts_with = "quiet")]
        verbose: bool,
        /// Print nothing but warnings and errors (no summary line, notes or progress bar).
        #[arg(short, long)]
        quiet: bool,
        /// Which tracer.
        #[arg(long, value_enum, default_value = "auto")]
        backend: glint::Backend,
        /// A PNG's bytes: linear or srgb (the sRGB curve); default: the scene's
        /// `[output] encoding`, else linear. Short for `--set output.encoding=...`.
        #[arg(long, value_parser = ["linear", "srgb"])]
        encoding: Option<String>,
        /// Neither read nor write the cache of large meshes and BVHs (kept in
        /// GLINT_CACHE_DIR, else $XDG_CACHE_HOME/glint or ~/.cache/glint).
        #[arg(long)]
        no_cache: bool,
        /// Frames FIRST..LAST (both included) or N of the scene's camera path
        /// ([[camera.keys]]), each written to -o with {} or {:04} in its file name replaced
        /// by the frame number (out/frame_{:04}.png); the BVH is built once.
        #[arg(long, value_name = "FIRST..LAST")]
        frames: Option<glint::render::FrameRange>,
        /// With --frames: leave each frame whose file exists as it is.
        #[arg(long, requires = "frames")]
        resume: bool,
        #[command(flatten)]
        frame: FrameArgs,
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Render a scene on the GPU and on the CPU mirror and measure the difference. Exit
    /// status: 0 equal (by --tolerance), 1 different, 2 a usage error, 3 any other error.
    Compare {
        /// The scene file (TOML).
        scene: PathBuf,
        #[command(flatten)]
        frame: FrameArgs,
        #[command(flatten)]
        common: CommonArgs,
        /// Where to write the difference image.
        #[arg(long, default_value = "diff.png")]
        diff: PathBuf,
        /// When the GPU's image counts as the mirror's: bits (every f32 bit, hit/miss and
        /// t), 8bit (the PNG's colour and hit/miss) or a number (the largest channel
        /// difference allowed). Exit status 0 when equal, 1 when not.
        #[arg(long, default_value = "bits")]
        tolerance: glint::compare::Tolerance,
    },
    /// Open a window on a scene: orbit (left button), pan (right), zoom (wheel), fly
    /// (W A S D Q E), reset (R); the picture refines while the camera is still and reloads
    /// when the scene or a file it reads is saved. P saves a PNG, X an EXR, C prints the
    /// camera, H the keys.
    View {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Which tracer (auto: a real GPU where there is one, else the CPU tracer).
        #[arg(long, value_enum, default_value = "auto")]
        backend: glint::Backend,
        /// Window size WxH (default: the scene's camera).
        #[arg(long, value_parser = parse_size)]
        size: Option<(u32, u32)>,
        /// Antialiasing: N×N samples a pixel, refined one at a time (default: the scene's).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=glint::scene::MAX_SAMPLES as i64))]
        samples: Option<u32>,
        /// Draw this many frames, then exit (with --screenshot: for tests and scripts).
        #[arg(long)]
        frames: Option<u32>,
        /// With --frames: write the last frame presented to this PNG.
        #[arg(long, requires = "frames")]
        screenshot: Option<PathBuf>,
        /// The GPU kernel's division and square root (see `render --math`).
        #[arg(long, value_enum, default_value = "exact")]
        math: MathArg,
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Read and check a scene as `render` would (the TOML, every key, the meshes, MTLs and
    /// textures it names) without rendering it: exit status 0 when it is good, 1 with the
    /// error (file, line and key) when not. Warnings are printed either way.
    Check {
        /// The scene files (TOML).
        #[arg(required = true)]
        scenes: Vec<PathBuf>,
        /// Read only files below each scene's own folder (meshes, MTLs; links followed).
        #[arg(long)]
        confine: bool,
        /// Change a key of each scene before it is read (see `render --set`).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<glint::scene::set::Setting>,
    },
    /// List the Vulkan adapters, best first, with their drivers and versions.
    Adapters,
    /// Print a shell's completion script for glint to standard output, e.g.
    /// `glint completions bash > ~/.local/share/bash-completion/completions/glint`.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print glint's manual page (roff) to standard output, e.g.
    /// `glint manpage > ~/.local/share/man/man1/glint.1`.
    Manpage,
    /// Compare two images (PNG or EXR) with `compare`'s metrics and write a difference
    /// image: an EXR made on a GPU machine against one made on the CPU elsewhere, bit for bit.
    Diff {
        /// The first image.
        a: PathBuf,
        /// The second image.
        b: PathBuf,
        /// Where to write the difference image (PNG).
        #[arg(long, default_value = "diff.png")]
        diff: PathBuf,
        /// When the two count as equal: bits (every f32 bit; between two EXRs also
        /// hit/miss and t), 8bit (the 8-bit colour) or a number (the largest channel
        /// difference allowed). Exit status 0 when equal, 1 when not.
        #[arg(long, default_value = "bits")]
        tolerance: glint::compare::Tolerance,
    },
    /// Traversal statistics of a frame, counted on the CPU mirror of the shader's per-ray
    /// traversal: per ray kind, the nodes, leaves and primitives each ray visits, its
    /// deepest stack, the bytes it reads, and the spread within a warp's 8x4 pixels.
    Stats {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Image size WxH (default 1024x768).
        #[arg(long, value_parser = parse_size, default_value = "1024x768")]
        size: (u32, u32),
        /// Triangle algorithm (default: the scene's).
        #[arg(long)]
        triangle: Option<TriangleAlgorithm>,
        /// Print one JSON object keyed by ray kind instead of the table.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        common: CommonArgs,
    },
    /// Speed against error: every scene × tracer × triangle algorithm, with a warm-up and
    /// timed runs; writes report.md, report.json and plot.png to --out.
    Bench {
        /// Scene files (default: the five seed scenes, as shipped with glint).
        scenes: Vec<PathBuf>,
        /// Image size WxH (default 1024x768).
        #[arg(long, value_parser = parse_size, default_value = "1024x768")]
        size: (u32, u32),
        /// Timed runs per configuration.
        #[arg(long, default_value_t = 5)]
        runs: usize,
        /// Output folder.
        #[arg(long, default_value = "bench-out")]
        out: PathBuf,
        #[command(flatten)]
        common: CommonArgs,
        /// Skip the GPU (CPU tracers only).
        #[arg(long)]
        no_gpu: bool,
        /// Only this triangle algorithm (default: all three where a scene has triangles).
        #[arg(long)]
        triangle: Option<TriangleAlgorithm>,
        /// The most reflections plus refractions along a path, for every scene (default:
        /// each scene's own).
        #[arg(long, value_parser = clap::value_parser!(u32).range(0..=glint::scene::MAX_DEPTH as i64))]
        max_depth: Option<u32>,
        /// The GPU kernel's division and square root (see `render --math`).
        #[arg(long, value_enum, default_value = "exact")]
        math: MathArg,
        /// Antialiasing for every scene: N×N samples a pixel (default: each scene's own).
        #[arg(long, value_parser = clap::value_parser!(u32).range(1..=glint::scene::MAX_SAMPLES as i64))]
        samples: Option<u32>,
    },
}

/// `WxH`, each side in 1..=`MAX_IMAGE_SIDE`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{s:?}: expected WxH, e.g. 640x480"))?;
    let p = |v: &str| -> Result<u32, String> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|_| format!("{s:?}: {v:?} is not a whole number"))?;
        if n == 0 || n as i64 > glint::scene::MAX_IMAGE_SIDE {
            return Err(format!(
                "{s:?}: each side must be in 1..={}",
                glint::scene::MAX_IMAGE_SIDE
            ));
        }
        Ok(n)
    };
    Ok((p(w)?, p(h)?))
}
