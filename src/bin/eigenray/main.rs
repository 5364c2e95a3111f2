//! `eigenray`: the command-line tool: solve a scene file to JSON, or run the built-in demo.
//!
//! A thin layer over the library: read, validate, trace, write. Exit status 0 on success
//! (also when some rays find no path), 2 for an invalid scene, an unreadable input or a usage
//! error, 1 when the output cannot be written (a closed pipe exits 1 without a message).

mod phase;
mod response;
mod svg;

use std::fmt::Write as _;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};

use clap::{Args, Parser, Subcommand, ValueEnum};
use eigenray::{
    Batch, BatchOptions, RaySet, Scene, SceneError, SearchArrival, StationaryRays, Status, Tracer,
    options::Run,
    options::{MAX_INPUT_BYTES, available_memory, read_limited},
    response::Echo,
    scene::StationaryMode,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// Receivers of the demo scene by default.
const DEMO_RECEIVERS: u64 = 500;
/// Largest `demo --receivers` accepted.
const DEMO_MAX_RECEIVERS: u64 = 10_000_000;
/// Seed of the demo's receiver grid by default.
const DEMO_SEED: u64 = 1;
/// Where the demo writes its picture by default.
const DEMO_SVG: &str = "eigenray-demo.svg";

#[derive(Parser, Debug)]
#[command(
    name = "eigenray",
    version,
    about = "Eigenrays through prescribed reflections and refractions on 2-D piecewise-linear interfaces",
    long_about = "Eigenrays through prescribed reflections and refractions on 2-D piecewise-linear \
                  interfaces.\n\nWithout a command, runs the built-in demo (`eigenray demo`).\n\n\
                  Exit status: 0 success (also when some rays find no path); 2 invalid scene, \
                  unreadable or too large input, a batch beyond the available memory, or usage \
                  error; 1 output could not be written (a full disk, a closed pipe)."
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Solve every (source, receiver, path) ray of a scene file; write the rays to standard
    /// output, in ray order (JSON unless `--format` says otherwise).
    ///
    /// The scene file and every output field are described in docs/scene-format.md of
    /// eigenray's repository.
    Solve(Box<SolveArgs>),
    /// Solve the built-in air-over-water scene, print a summary and draw it (the default).
    Demo(DemoArgs),
}

#[derive(Args, Debug)]
struct SolveArgs {
    /// Scene file (JSON, at most 256 MiB); `-` reads standard input.
    #[arg(value_name = "SCENE.json")]
    scene: PathBuf,
    /// Output format: `json`, one `{"rays": [...]}` document; `jsonl`, one ray per line;
    /// `csv`, a header and one line per ray; `npy`, NumPy's binary `.npy` file (redirect it to
    /// a file), one fixed-size record per ray.
    #[arg(long, value_enum, default_value_t = Format::Json)]
    format: Format,
    /// Start every ray from the default initial guess instead of a neighbouring receiver's
    /// solution.
    #[arg(long)]
    no_warm_start: bool,
    /// Also write the scene's name tables as JSON to this file: the status of each `.npy`
    /// status code, the name of each path and of each medium index (media in the order of
    /// their names). The `.npy` format holds numbers only; this file names them.
    #[arg(long, value_name = "PATH")]
    names: Option<PathBuf>,
    /// Where the rays go: `-` is standard output (the default, unless a response output
    /// `--ir`, `--echogram` or `--tl-map` is asked for: then the rays are written only where
    /// this says), or a file, in the format of `--format`.
    #[arg(long, value_name = "PATH")]
    rays: Option<PathBuf>,
    /// Where the arrivals of the scene's `search` section go: a file, or `-` for standard
    /// output, in the format of `--format` (JSON: `{"arrivals": [...]}`; JSON Lines: one
    /// arrival per line; CSV: a table of their own; npy: records of their own). Without it
    /// they go beside the rays, in JSON and JSON Lines; CSV and npy hold one table each, so a
    /// scene with a `search` section needs it with them.
    #[arg(long, value_name = "PATH")]
    arrivals: Option<PathBuf>,
    /// Also draw the scene and its rays to this SVG file (with axes; past 2,000 rays a
    /// sample of them).
    #[arg(long, value_name = "PATH")]
    svg: Option<PathBuf>,
    /// Write the scene's impulse responses (`"impulse_response"`) to this file: `.npy`,
    /// float64 `[sources, receivers, samples]`; or `.wav`, 32-bit float, one channel per
    /// (source, receiver), source-major. Every `converged` ray and arrival with an amplitude
    /// adds its pulse. A response output: standard output stays empty unless `--rays -` or
    /// `--arrivals -` asks for it, and a summary goes to standard error.
    #[arg(long, value_name = "PATH")]
    ir: Option<PathBuf>,
    /// Write the transmission loss of every (source, receiver) to this `.npy` file: float64 dB,
    /// `[sources, receivers]` (`[sources, nx, ny]` for a receiver grid), at
    /// `amplitudes.frequency`, summed as `"transmission_loss": {"mode": ...}` says
    /// (`coherent` by default, or `incoherent`); +inf where nothing arrives. The arrivals
    /// are summed as the search finds them (not listed, unless written). A response output,
    /// as `--ir`.
    #[arg(long, value_name = "PATH")]
    tl: Option<PathBuf>,
    /// Write the room acoustic parameters of every (source, receiver)'s impulse response
    /// (the scene's `impulse_response`) to this JSON file: one entry per pair, source-major,
    /// with `edt`, `t20`, `t30` (s), `c50`, `c80` (dB) and `d50`, time zero at the pair's
    /// first arrival; `null` with a reason where the response is too short or too sparse.
    /// A response output, as `--ir`.
    #[arg(long, value_name = "PATH")]
    parameters: Option<PathBuf>,
    /// Draw the echogram of one source at one receiver (`--source`, `--receiver`) to this SVG
    /// file: each arrival as a stem at its time, up to its level in dB, coloured by its
    /// number of interactions; the time axis starts just before the first arrival. Needs
    /// `amplitudes`. A response output, as `--ir`.
    #[arg(long, value_name = "PATH")]
    echogram: Option<PathBuf>,
    /// Start the echogram's time axis at t = 0 instead of just before the first arrival.
    #[arg(long)]
    echogram_from_zero: bool,
    /// Draw the transmission-loss map of one source (`--source`) over every receiver to this
    /// SVG file, at `amplitudes.frequency`: −20 log10(|p| · 4π) dB of the coherent sum of
    /// each receiver's arrivals, as a grid of cells where the receivers form one, with the
    /// interfaces, the bottom under the source and the source drawn over it. A response
    /// output, as `--ir`.
    #[arg(long, value_name = "PATH")]
    tl_map: Option<PathBuf>,
    /// The source of `--echogram` and `--tl-map`.
    #[arg(long, value_name = "N", default_value_t = 0)]
    source: usize,
    /// The receiver of `--echogram`.
    #[arg(long, value_name = "N", default_value_t = 0)]
    receiver: usize,
    /// The horizontal axis of `--svg` and `--tl-map`: its name, unit and the scale from the
    /// scene's x to the numbers on its ticks (`range,km,0.001` for a scene in metres).
    #[arg(long, value_name = "NAME[,UNIT[,SCALE]]", default_value = "x")]
    x_axis: svg::AxisSpec,
    /// The vertical axis of `--svg` and `--tl-map`, as `--x-axis`; a negative scale numbers it
    /// downwards (`depth,m,-1`: depth positive down below y = 0).
    #[arg(long, value_name = "NAME[,UNIT[,SCALE]]", default_value = "y")]
    y_axis: svg::AxisSpec,
    /// What colours the rays in the picture: `time` (travel time, with a colour bar giving the
    /// range), `path` (one colour per path, with a legend of path names) or `sequence` (one
    /// colour per step sequence, with a legend listing the sequences).
    #[arg(long, visible_alias = "svg-color", value_enum, value_name = "BY",
          default_value_t = svg::Colouring::Time)]
    colour_by: svg::Colouring,
}

#[derive(Args, Debug)]
struct DemoArgs {
    /// Number of receivers (on a jittered grid under the water surface).
    #[arg(long, value_name = "N", default_value_t = DEMO_RECEIVERS,
          value_parser = clap::value_parser!(u64).range(0..=DEMO_MAX_RECEIVERS))]
    receivers: u64,
    /// Where to write the picture.
    #[arg(long, value_name = "PATH", default_value = DEMO_SVG)]
    svg: PathBuf,
    /// Do not write the picture.
    #[arg(long)]
    no_svg: bool,
    /// Seed of the receivers' jitter.
    #[arg(long, value_name = "S", default_value_t = DEMO_SEED)]
    seed: u64,
}

impl Default for DemoArgs {
    fn default() -> Self {
        DemoArgs {
            receivers: DEMO_RECEIVERS,
            svg: PathBuf::from(DEMO_SVG),
            no_svg: false,
            seed: DEMO_SEED,
        }
    }
}

/// Output formats of `solve`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Format {
    /// One JSON document, `{"rays": [...]}`, one object per ray.
    Json,
    /// One ray object per line (JSON Lines), in ray order.
    Jsonl,
    /// Comma-separated values: a header, then one line per ray (points as `x y;x y;…`, leg
    /// media as names joined by `;`).
    Csv,
    /// NumPy's `.npy` file: one fixed-size binary record per ray, numbers only (`--names`
    /// writes the names of its codes and indices).
    Npy,
}

impl From<Format> for eigenray::Format {
    fn from(f: Format) -> Self {
        match f {
            Format::Json => eigenray::Format::Json,
            Format::Jsonl => eigenray::Format::Jsonl,
            Format::Csv => eigenray::Format::Csv,
            Format::Npy => eigenray::Format::Npy,
        }
    }
}

/// Why the program stops early.
#[derive(Debug)]
enum Failure {
    /// Invalid scene or unreadable input (exit status 2); the message is `key: what`.
    Input(String),
    /// An output could not be written (exit status 1).
    Output(String),
    /// Standard output was closed by the reader (exit status 1, no message).
    BrokenPipe,
}

impl Failure {
    fn exit(self) -> ExitCode {
        let (code, message) = match self {
            Failure::Input(m) => (2, Some(m)),
            Failure::Output(m) => (1, Some(m)),
            Failure::BrokenPipe => (1, None),
        };
        if let Some(m) = message {
            // One line, whatever the message holds, with control characters escaped (names and
            // paths come from the user); a failing stderr has nowhere to report to.
            let line = SceneError::escape_text(&m);
            let _ = writeln!(io::stderr().lock(), "error: {line}");
        }
        ExitCode::from(code)
    }

    fn scene(e: SceneError) -> Failure {
        Failure::Input(e.to_string())
    }

    /// A failed write to standard output.
    fn stdout(e: io::Error) -> Failure {
        if is_broken_pipe(&e) {
            Failure::BrokenPipe
        } else {
            Failure::Output(format!("standard output: {}", io_message(&e)))
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Command::Solve(args)) => solve(&args),
        Some(Command::Demo(args)) => demo(&args),
        None => demo(&DemoArgs::default()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => f.exit(),
    }
}

/// Refuses a batch whose arrays would not fit in the memory this machine has available, before
/// anything is allocated, saying how much it needs and why (with `"stationary": "all"`, what
/// one stationary path per ray needs: at least that much).
fn check_batch_memory(scene: &Scene, warm_start: bool) -> Result<(), Failure> {
    let size = scene.batch_size();
    let all = scene.solver().stationary == StationaryMode::All;
    // With every stationary path, each triple holds at least one entry: the triple, one
    // arrival and the heap blocks of its four vectors (points; parameters and segments, one
    // each a point at most; media, one a leg).
    const HEAP_BLOCK: usize = 32;
    let point = std::mem::size_of::<eigenray::Point>();
    let (per_ray, per_point, per_leg) = if all {
        (
            std::mem::size_of::<eigenray::stationary::TripleArrivals>()
                + std::mem::size_of::<eigenray::Arrival>()
                + 4 * HEAP_BLOCK,
            point + 2 * std::mem::size_of::<usize>(),
            std::mem::size_of::<usize>(),
        )
    } else {
        (std::mem::size_of::<eigenray::RayRecord>(), point, 4)
    };
    // Solving in a spatial order keeps a second copy of the arrays.
    let copies = if warm_start && !all { 2 } else { 1 };
    let need = size
        .bytes(per_ray, per_point, per_leg)
        .and_then(|b| b.checked_mul(copies));
    // Nothing to hold (a scene without rays, its search alone): no look at the memory.
    if need == Some(0) {
        return Ok(());
    }
    let have = available_memory();
    let too_much = match (need, have) {
        (None, _) => true,
        (Some(n), Some(h)) => n as u64 > h,
        (Some(_), None) => false,
    };
    if !too_much {
        return Ok(());
    }
    let gb = |b: f64| format!("{:.1} GB", b / 1e9);
    let need_text = match need {
        Some(n) => gb(n as f64),
        None => "more bytes than this machine can address".to_string(),
    };
    let why = format!(
        "{} rays of {per_ray} bytes and {} points of {per_point} bytes{}",
        size.rays,
        size.points,
        if copies == 2 {
            ", twice (solved in a spatial order)"
        } else {
            ""
        }
    );
    let have_text = have.map_or(String::new(), |h| {
        format!(
            ", more than the {} this machine has available",
            gb(h as f64)
        )
    });
    let what = if all {
        "solver.stationary: every stationary path of each ray needs at least"
    } else {
        "paths: the batch needs about"
    };
    Err(Failure::Input(format!(
        "{what} {need_text} ({why}){have_text}: split the receivers or the paths over several \
         runs"
    )))
}

/// What `eigenray solve` found: one ray per triple, or every stationary path of each.
enum Solved {
    /// `"stationary": "one"`.
    Batch(Batch),
    /// `"stationary": "all"`.
    Stationary(StationaryRays),
}

impl Solved {
    fn rays(&self) -> RaySet<'_> {
        match self {
            Solved::Batch(b) => RaySet::Batch(b),
            Solved::Stationary(st) => RaySet::Stationary(st),
        }
    }

    /// Hands every echo of the rays (of `scene`'s paths) to `add`, and counts the timed rays
    /// without an amplitude value.
    fn echoes(&self, scene: &Scene, add: &mut dyn FnMut(Echo)) -> u64 {
        let without = |status: Status, a: Option<&eigenray::Amplitude>| {
            status.has_time() && !a.is_some_and(eigenray::Amplitude::has_value)
        };
        eigenray::response::echoes_of_rays(scene, self.rays()).for_each(add);
        match self {
            Solved::Batch(b) => (0..b.len())
                .filter(|&i| without(b.record(i).status, b.amplitude(i)))
                .count() as u64,
            Solved::Stationary(st) => (st.triples.iter())
                .flat_map(|t| &t.arrivals)
                .filter(|a| without(a.status, a.amplitude.as_ref()))
                .count() as u64,
        }
    }

    /// Whether there is no ray (a scene without `paths`).
    fn is_empty(&self) -> bool {
        match self {
            Solved::Batch(b) => b.is_empty(),
            Solved::Stationary(st) => st.triples.is_empty(),
        }
    }
}

/// An output file asked for on the command line.
#[derive(Clone, Copy, Debug)]
struct OutputFile<'a> {
    /// The option that names it (`--tl-map`).
    option: &'static str,
    /// Its path.
    path: &'a Path,
}

/// The response outputs asked for: with any of them, standard output stays empty unless
/// `--rays -` or `--arrivals -` asks for it, and a summary goes to standard error. (A new
/// response output joins this rule by a line here.)
fn response_outputs(args: &SolveArgs) -> Vec<OutputFile<'_>> {
    [
        ("--ir", &args.ir),
        ("--tl", &args.tl),
        ("--parameters", &args.parameters),
        ("--echogram", &args.echogram),
        ("--tl-map", &args.tl_map),
    ]
    .into_iter()
    .filter_map(|(option, path)| path.as_deref().map(|path| OutputFile { option, path }))
    .collect()
}

/// Where a table of `solve` goes.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Destination {
    /// Standard output (`-`).
    Stdout,
    /// A file.
    File(PathBuf),
    /// Not written.
    Nowhere,
}

impl Destination {
    /// The destination named by an option's value: `-` is standard output.
    fn of(path: &Path) -> Destination {
        if path.as_os_str() == "-" {
            Destination::Stdout
        } else {
            Destination::File(path.to_path_buf())
        }
    }
}

/// Where the rays and the arrivals of `solve` go.
struct Destinations {
    /// The rays': where `--rays` says, else standard output unless a response output is asked
    /// for.
    rays: Destination,
    /// The arrivals': where `--arrivals` says (`None`: beside the rays).
    arrivals: Option<Destination>,
}

impl Destinations {
    /// The destinations of `args`.
    fn of(args: &SolveArgs) -> Destinations {
        let rays = match &args.rays {
            Some(path) => Destination::of(path),
            None if response_outputs(args).is_empty() => Destination::Stdout,
            None => Destination::Nowhere,
        };
        Destinations {
            rays,
            arrivals: args.arrivals.as_deref().map(Destination::of),
        }
    }

    /// Whether the arrivals would go beside the rays into one CSV or npy table, which holds
    /// one kind of entry only: refused before the solve.
    fn share_one_table(&self, format: Format) -> bool {
        self.rays != Destination::Nowhere
            && self.arrivals_beside_rays()
            && matches!(format, Format::Csv | Format::Npy)
    }

    /// Whether the arrivals share the rays' document: they have no destination of their own,
    /// or both go to standard output.
    fn arrivals_beside_rays(&self) -> bool {
        match &self.arrivals {
            None => true,
            Some(a) => *a == Destination::Stdout && self.rays == Destination::Stdout,
        }
    }

    /// Where the arrivals end up: their own destination, or the rays'.
    fn of_arrivals(&self) -> &Destination {
        self.arrivals.as_ref().unwrap_or(&self.rays)
    }
}

/// Every file `solve` is asked to write (not `-`).
fn output_files(args: &SolveArgs) -> Vec<OutputFile<'_>> {
    let mut files: Vec<OutputFile<'_>> = [
        ("--names", &args.names),
        ("--svg", &args.svg),
        ("--rays", &args.rays),
        ("--arrivals", &args.arrivals),
    ]
    .into_iter()
    .filter_map(|(option, path)| path.as_deref().map(|path| OutputFile { option, path }))
    .collect();
    files.extend(response_outputs(args));
    files.retain(|f| f.path.as_os_str() != "-");
    files
}

/// Refuses, before anything is solved, an output file that cannot be written (a missing
/// directory, no permission, a directory) or that two options name: exit status 2, naming
/// the option and the path. A file that does not exist yet is created to try, then removed.
fn check_output_files(args: &SolveArgs) -> Result<(), Failure> {
    let files = output_files(args);
    for (k, file) in files.iter().enumerate() {
        if let Some(other) = files[..k].iter().find(|f| f.path == file.path) {
            return Err(Failure::Input(format!(
                "{}: {} is also the file of {}; give each output a file of its own",
                file.option,
                file.path.display(),
                other.option
            )));
        }
        check_writable(file.option, file.path)?;
    }
    Ok(())
}

/// Whether `path` can be written, without changing it: an existing file is opened to append
/// (nothing appended), a new one created and removed.
fn check_writable(option: &str, path: &Path) -> Result<(), Failure> {
    let refuse = |e: &io::Error| {
        Failure::Input(format!(
            "{option}: {}: cannot write: {}",
            path.display(),
            io_message(e)
        ))
    };
    if path.is_dir() {
        return Err(Failure::Input(format!(
            "{option}: {}: is a directory, not a file",
            path.display()
        )));
    }
    match fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
    {
        Ok(file) => {
            drop(file);
            let _ = fs::remove_file(path);
            Ok(())
        }
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => fs::OpenOptions::new()
            .append(true)
            .open(path)
            .map(drop)
            .map_err(|e| refuse(&e)),
        Err(e) => Err(refuse(&e)),
    }
}

/// `eigenray solve`: everything is computed before anything is written.
fn solve(args: &SolveArgs) -> Result<(), Failure> {
    let to = Destinations::of(args);
    let to_stdout = to.rays == Destination::Stdout || to.arrivals == Some(Destination::Stdout);
    if args.format == Format::Npy && to_stdout && std::io::IsTerminal::is_terminal(&io::stdout()) {
        return Err(Failure::Input(
            "--format npy: binary output; redirect standard output to a file".into(),
        ));
    }
    let text = read_scene_text(&args.scene)?;
    // Shared with the tracer, not copied: a scene of millions of segments is held once.
    let scene = std::sync::Arc::new(Scene::from_json(&text).map_err(Failure::scene)?);
    // The document is no longer needed: its memory goes back before the rays take theirs.
    drop(text);
    if args.arrivals.is_some() && scene.search().is_none() {
        return Err(Failure::Input(
            "--arrivals: the scene has no `search` section, so it has no arrivals to write".into(),
        ));
    }
    if scene.search().is_some() && Destinations::of(args).share_one_table(args.format) {
        let name = if args.format == Format::Csv {
            "csv"
        } else {
            "npy"
        };
        return Err(Failure::Input(format!(
            "--format {name}: the scene's `search` arrivals are a table of their own; give \
             --arrivals FILE to write them"
        )));
    }
    check_batch_memory(&scene, !args.no_warm_start)?;
    let ir = match &args.ir {
        Some(path) => Some(response::IrOutput::check(path, &scene)?),
        None => None,
    };
    let style = response::ChartStyle {
        axes: axes(args),
        echogram_from_zero: args.echogram_from_zero,
    };
    let charts = response::Charts::check(
        args.echogram.as_deref(),
        args.tl_map.as_deref(),
        (args.source, args.receiver),
        style,
        &scene,
    )?;
    let tl = match &args.tl {
        Some(path) => Some(response::TlOutput::check(path, &scene)?),
        None => None,
    };
    let parameters = match &args.parameters {
        Some(_) => Some(response::parameters_check(&scene)?),
        None => None,
    };
    check_output_files(args)?;
    let sums = response::Sums::new(
        &scene,
        ir.as_ref(),
        tl.as_ref(),
        charts.as_ref(),
        parameters.as_ref(),
    )?;
    let tracer = Tracer::new(std::sync::Arc::clone(&scene)).map_err(Failure::scene)?;
    let solved = match scene.solver().stationary {
        StationaryMode::One => Solved::Batch(trace(&tracer, !args.no_warm_start)?),
        StationaryMode::All => Solved::Stationary(trace_stationary(&tracer)?),
    };
    if let Some(sums) = &sums {
        let without = solved.echoes(&scene, &mut |e| sums.add(e));
        (0..without).for_each(|_| sums.skip());
    }
    // The search's arrivals are listed only where written (or drawn); otherwise they go
    // straight into the responses.
    let listed = *to.of_arrivals() != Destination::Nowhere || args.svg.is_some();
    // One search feeds every output, `--parameters` included.
    let (arrivals, streamed, incomplete_pairs) = match (scene.search(), &sums) {
        (Some(_), Some(sums)) if !listed => {
            let report = search_streamed(&tracer, sums)?;
            (None, Some(report.arrivals), report.incomplete_pairs)
        }
        (Some(_), _) => {
            let report = search(&tracer)?;
            (Some(report.arrivals), None, report.incomplete_pairs)
        }
        (None, _) => (None, None, 0),
    };
    if let (Some(sums), Some(arrivals)) = (&sums, &arrivals) {
        for a in arrivals {
            match Echo::of_streamed(&a.streamed()) {
                Some(e) => sums.add(e),
                None if a.arrival.status.has_time() => sums.skip(),
                None => {}
            }
        }
    }
    let summed = sums.as_ref().map(|s| {
        (
            s.echoes.load(std::sync::atomic::Ordering::Relaxed),
            s.without_amplitude
                .load(std::sync::atomic::Ordering::Relaxed),
        )
    });
    if let Some(sums) = sums {
        sums.write(&scene, args.parameters.as_deref(), incomplete_pairs)?;
    }
    write_outputs(args, &scene, &solved, arrivals.as_deref())?;
    let responses = response_outputs(args);
    if !responses.is_empty() {
        let mut line = response_summary(&responses, &solved, arrivals.as_deref(), streamed, args);
        if let Some((echoes, without)) = summed {
            let _ = write!(
                line,
                "; {echoes} echoes summed, {without} timed {} without an amplitude (adding \
                 nothing)",
                if without == 1 { "path" } else { "paths" }
            );
        }
        let _ = writeln!(io::stderr().lock(), "{line}");
    }
    Ok(())
}

/// The axes of the pictures, as `--x-axis` and `--y-axis` name them.
fn axes(args: &SolveArgs) -> svg::Axes {
    svg::Axes {
        x: args.x_axis.clone(),
        y: args.y_axis.clone(),
    }
}

/// The line on standard error of a run that wrote response outputs: what was solved, what was
/// written where, and what was not written (with the options that would write it).
fn response_summary(
    responses: &[OutputFile<'_>],
    solved: &Solved,
    arrivals: Option<&[SearchArrival]>,
    streamed: Option<u64>,
    args: &SolveArgs,
) -> String {
    let written: Vec<String> = responses
        .iter()
        .map(|f| format!("{} {}", f.option, f.path.display()))
        .collect();
    let mut summary = solved_summary(solved, arrivals);
    if let Some(n) = streamed {
        let _ = write!(
            summary,
            "; {n} search {} (summed as found)",
            if n == 1 { "arrival" } else { "arrivals" }
        );
    }
    let mut line = format!("solve: {summary}; wrote {}", written.join(", "));
    let to = Destinations::of(args);
    let mut unwritten = Vec::new();
    if to.rays == Destination::Nowhere && !solved.is_empty() {
        unwritten.push(("the rays", "--rays -"));
    }
    if (arrivals.is_some() || streamed.is_some()) && *to.of_arrivals() == Destination::Nowhere {
        unwritten.push(("the arrivals", "--arrivals -"));
    }
    if !unwritten.is_empty() {
        let (what, how): (Vec<&str>, Vec<&str>) = unwritten.into_iter().unzip();
        let _ = write!(
            line,
            "; not written: {} ({} for standard output)",
            what.join(" and "),
            how.join(", ")
        );
    }
    line
}

/// Writes what `solve` found: the name tables and the picture when asked for, then the rays
/// and the arrivals of a scene's search (`Some` exactly for a scene with a `search` section)
/// where [`Destinations`] sends them, files first and standard output last. Arrivals without
/// a destination of their own go beside the rays, in JSON and JSON Lines (sharing a CSV or npy
/// table with the rays is refused before the solve: [`Destinations::share_one_table`]).
fn write_outputs(
    args: &SolveArgs,
    scene: &Scene,
    solved: &Solved,
    arrivals: Option<&[SearchArrival]>,
) -> Result<(), Failure> {
    let format = eigenray::Format::from(args.format);
    let to = Destinations::of(args);
    let beside = to.arrivals_beside_rays();
    let Destinations {
        rays: rays_to,
        arrivals: arrivals_to,
    } = to;
    if let Some(path) = &args.names {
        let mut names = Vec::new();
        eigenray::output::write_names(scene, &mut names).map_err(|e| write_failure(path, &e))?;
        fs::write(path, names).map_err(|e| write_failure(path, &e))?;
    }
    if let Some(path) = &args.svg {
        let title = format!(
            "{}: {}",
            display_name(&args.scene),
            solved_summary(solved, arrivals)
        );
        let svg = svg::scene_svg_with_axes(
            scene,
            solved.rays(),
            arrivals.unwrap_or_default(),
            &title,
            args.colour_by,
            &axes(args),
        );
        fs::write(path, svg).map_err(|e| write_failure(path, &e))?;
    }
    // The documents of each destination: the rays' (with the arrivals beside them), and the
    // arrivals' own.
    let rays_document = eigenray::Document {
        rays: Some(solved.rays()),
        arrivals: if beside { arrivals } else { None },
    };
    let arrivals_document = match (&arrivals_to, arrivals) {
        (Some(to), Some(arrivals)) if !beside => Some((to, arrivals)),
        _ => None,
    };
    if let Some((Destination::File(path), arrivals)) = arrivals_document {
        let mut file = Vec::new();
        eigenray::write(scene, arrivals, format, &mut file).map_err(|e| write_failure(path, &e))?;
        fs::write(path, file).map_err(|e| write_failure(path, &e))?;
    }
    if let Destination::File(path) = &rays_to {
        let mut file = Vec::new();
        eigenray::write(scene, rays_document, format, &mut file)
            .map_err(|e| write_failure(path, &e))?;
        fs::write(path, file).map_err(|e| write_failure(path, &e))?;
    }
    if let Some((Destination::Stdout, arrivals)) = arrivals_document {
        return eigenray::write(scene, arrivals, format, io::stdout().lock())
            .map_err(Failure::stdout);
    }
    if rays_to == Destination::Stdout {
        return eigenray::write(scene, rays_document, format, io::stdout().lock())
            .map_err(Failure::stdout);
    }
    Ok(())
}

/// The arrivals of the scene's `search`, refused before it starts where its table of pairs
/// would not fit in the memory this machine has available; a spinner with the beams visited
/// on standard error when it is a terminal, and one summary line there at the end, whatever
/// the format and whether or not standard error is a terminal: arrivals, beams, the bounds,
/// the pairs a limit left short, and how many pairs no arrival reaches (they have no entry in
/// the output).
fn search(tracer: &Tracer) -> Result<eigenray::search::SearchReport, Failure> {
    let scene = tracer.scene();
    let options = scene.search().expect("a scene with a search section");
    let pairs = scene.sources().len() as u128 * scene.receivers().len() as u128;
    let need = pairs * eigenray::search::PAIR_BYTES as u128;
    if let Some(have) = available_memory()
        && need > have as u128
    {
        return Err(Failure::Input(format!(
            "search: {pairs} source-receiver pairs need {:.1} GB for their table alone \
             ({} bytes each), more than the {:.1} GB this machine has available: search fewer \
             sources and receivers at a time",
            need as f64 / 1e9,
            eigenray::search::PAIR_BYTES,
            have as f64 / 1e9
        )));
    }
    // Beams on the bar's count (the trees' work, as the run hears of it), pairs in its
    // message.
    let bar = Bar::new(None, "units of work");
    let shown = bar.bar.clone();
    let done = std::sync::atomic::AtomicU64::new(0);
    let run = Run::new().on_progress(move |p: eigenray::options::Progress| {
        shown.inc(p.work);
        if p.items > 0 {
            let pairs = done.fetch_add(p.items, std::sync::atomic::Ordering::Relaxed) + p.items;
            shown.set_message(format!(", {pairs} pairs searched for refractions"));
        }
    });
    let started = Instant::now();
    let report = tracer
        .search(&run)
        .map_err(|e| Failure::Input(format!("search: {e}")))?;
    bar.finish();
    let n = report.arrivals.len();
    let mut line = format!(
        "search: {n} {} in {:.3} s, {} beams",
        if n == 1 { "arrival" } else { "arrivals" },
        started.elapsed().as_secs_f64(),
        report.beams
    );
    search_bounds(&mut line, report.work, scene.curved(), options);
    if report.incomplete_pairs > 0 {
        let n = report.incomplete_pairs;
        let _ = write!(
            line,
            "; {n} {} {} (their arrivals say complete: false)",
            if n == 1 { "pair" } else { "pairs" },
            short_pairs(scene)
        );
    }
    let _ = write!(line, "; {}", unreached_pairs(scene, &report.arrivals));
    eprintln!("{line}");
    Ok(report)
}

/// What the summary line says of a search's short pairs: a limit stopped them, or, through
/// curved legs, the search (by shooting) is no proof, or a limit stopped it.
fn short_pairs(scene: &eigenray::Scene) -> &'static str {
    if scene.curved() {
        "searched through curved legs by shooting (no proof), or stopped at a limit"
    } else {
        "stopped at a limit"
    }
}

/// The summary line's middle, shared by the listing and the streamed search: the walk's work
/// on refracting sequences (every sequence through curved legs) when any, and the search's
/// bounds.
fn search_bounds(
    line: &mut String,
    work: u64,
    curved: bool,
    options: &eigenray::scene::SearchOptions,
) {
    if work > 0 {
        let what = if curved {
            "sequences"
        } else {
            "refracting sequences"
        };
        let _ = write!(line, ", {work} units of work on {what}");
    }
    match (options.max_steps, options.max_time) {
        (Some(k), Some(t)) => _ = write!(line, "; up to {k} steps and time {t}"),
        (Some(k), None) => _ = write!(line, "; up to {k} steps"),
        (None, Some(t)) => _ = write!(line, "; up to time {t}"),
        (None, None) => {}
    }
}

/// The scene's `search` streamed into the response outputs' `sums` (no arrival listed), with
/// the spinner of [`search`] and its summary line: the arrivals summed, beams, the bounds and
/// the pairs a limit left short. The number of arrivals.
fn search_streamed(
    tracer: &Tracer,
    sums: &response::Sums<'_>,
) -> Result<eigenray::search::StreamReport, Failure> {
    let scene = tracer.scene();
    let options = scene.search().expect("a scene with a search section");
    let bar = Bar::new(None, "units of work");
    let shown = bar.bar.clone();
    let run = Run::new().on_progress(move |p: eigenray::options::Progress| shown.inc(p.work));
    let started = Instant::now();
    let report = tracer
        .search_into_sink(&run, &response::StreamedSums(sums))
        .map_err(|e| Failure::Input(format!("search: {e}")))?;
    bar.finish();
    let n = report.arrivals;
    let mut line = format!(
        "search: {n} {} summed as found in {:.3} s, {} beams",
        if n == 1 { "arrival" } else { "arrivals" },
        started.elapsed().as_secs_f64(),
        report.beams
    );
    search_bounds(&mut line, report.work, scene.curved(), options);
    if report.incomplete_pairs > 0 {
        let n = report.incomplete_pairs;
        let _ = write!(
            line,
            "; {n} {} {} (their sums may miss arrivals)",
            if n == 1 { "pair" } else { "pairs" },
            short_pairs(scene)
        );
    }
    eprintln!("{line}");
    Ok(report)
}

/// Pairs named in the search's summary line, at most.
const UNREACHED_NAMED: usize = 5;

/// How many (source, receiver) pairs of `scene` no arrival of `arrivals` (ordered by source and
/// receiver) reaches, in words, with the first few of them named.
fn unreached_pairs(scene: &Scene, arrivals: &[SearchArrival]) -> String {
    let receivers = scene.receivers().len();
    let pairs = scene.sources().len() * receivers;
    let mut reached = arrivals
        .iter()
        .map(|a| a.source * receivers + a.receiver)
        .peekable();
    let mut unreached = 0;
    let mut named = Vec::new();
    for pair in 0..pairs {
        while reached.next_if(|&r| r < pair).is_some() {}
        if reached.peek() == Some(&pair) {
            continue;
        }
        unreached += 1;
        if named.len() < UNREACHED_NAMED {
            named.push(format!(
                "source {} to receiver {}",
                pair / receivers,
                pair % receivers
            ));
        }
    }
    let mut text = format!(
        "no arrival reaches {unreached} of the {pairs} source-receiver {}",
        if pairs == 1 { "pair" } else { "pairs" }
    );
    if !named.is_empty() {
        let more = if unreached > named.len() { ", …" } else { "" };
        let _ = write!(text, " ({}{more})", named.join(", "));
    }
    text
}

/// Every stationary path of every ray (`"stationary": "all"`), with a progress bar on standard
/// error when it is a terminal and the run is long; a path beyond the search's step limit is
/// refused with its key.
fn trace_stationary(tracer: &Tracer) -> Result<StationaryRays, Failure> {
    let bar = Bar::new(Some(tracer.scene().num_rays()), "rays searched");
    let rays = tracer
        .trace_stationary(&bar.run())
        .map_err(|e| Failure::scene(e.into()));
    bar.finish();
    rays
}

/// Solves every ray; a progress bar on standard error when it is a terminal and the run is
/// long.
fn trace(tracer: &Tracer, warm_start: bool) -> Result<Batch, Failure> {
    let opts = BatchOptions {
        warm_start,
        ..BatchOptions::default()
    };
    // A scene without rays (its search alone): no progress to show, no thread to wait for
    // the terminal's bar.
    if tracer.scene().num_rays() == 0 {
        return tracer
            .trace_batch(&opts, &Run::new())
            .map_err(Failure::scene);
    }
    let bar = Bar::new(Some(tracer.scene().num_rays()), "rays");
    // Where the memory check could not tell (no `MemAvailable`, or other processes took it
    // meanwhile), the allocation itself fails with a message instead of an abort.
    let batch = tracer
        .trace_batch(&opts, &bar.run())
        .map_err(Failure::scene);
    bar.finish();
    batch
}

/// How long a run goes before its progress is shown.
const PROGRESS_AFTER: Duration = Duration::from_millis(500);

/// The progress of a long run on standard error, whatever its size: a bar over its rays (a
/// spinner where they are not counted), with the time spent and left, redrawn a few times a
/// second. Nothing is drawn unless standard error is a terminal, nor before the run has gone
/// on for [`PROGRESS_AFTER`] (a quick run leaves no trace).
struct Bar {
    /// The bar, hidden until shown.
    bar: ProgressBar,
    /// Set when the run is over: the thread that shows the bar stops waiting.
    done: std::sync::Arc<std::sync::atomic::AtomicBool>,
}

impl Bar {
    /// The progress of a run over `total` rays (`None`: not counted), described by `what`.
    fn new(total: Option<usize>, what: &str) -> Bar {
        let bar = match total {
            Some(n) => ProgressBar::with_draw_target(Some(n as u64), ProgressDrawTarget::hidden()),
            None => ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden()),
        };
        let template = match total {
            Some(_) => {
                format!("{{bar:40}} {{pos}}/{{len}} {what}, {{elapsed}} spent, {{eta}} left")
            }
            None => format!("{{spinner}} {{pos}} {what}{{msg}}, {{elapsed}} spent"),
        };
        if let Ok(style) = ProgressStyle::with_template(&template) {
            bar.set_style(style);
        }
        let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        if std::io::IsTerminal::is_terminal(&io::stderr()) {
            let (bar, done) = (bar.clone(), std::sync::Arc::clone(&done));
            std::thread::spawn(move || {
                let start = Instant::now();
                while start.elapsed() < PROGRESS_AFTER {
                    if done.load(std::sync::atomic::Ordering::Relaxed) {
                        return;
                    }
                    std::thread::sleep(Duration::from_millis(20));
                }
                if !done.load(std::sync::atomic::Ordering::Relaxed) {
                    bar.set_draw_target(ProgressDrawTarget::stderr());
                    bar.enable_steady_tick(Duration::from_millis(200));
                }
            });
        }
        Bar { bar, done }
    }

    /// A library run whose items (rays, triples, echoes) advance the bar.
    fn run(&self) -> Run {
        let shown = self.bar.clone();
        Run::new().on_progress(move |p: eigenray::options::Progress| {
            if p.items > 0 {
                shown.inc(p.items);
            }
        })
    }

    /// The run is over: the bar, if shown, is cleared.
    fn finish(self) {
        self.done.store(true, std::sync::atomic::Ordering::Relaxed);
        self.bar.finish_and_clear();
    }
}

/// The scene file as text: `-` is standard input; errors name the path.
fn read_scene_text(path: &Path) -> Result<String, Failure> {
    let name = display_name(path);
    // At most one byte more than the limit is read: enough to know that it is exceeded (a
    // scene document beyond it is refused before it fills the memory).
    let bytes = if path.as_os_str() == "-" {
        read_limited(&mut io::stdin().lock())
    } else {
        fs::File::open(path).and_then(|mut f| read_limited(&mut f))
    }
    .map_err(|e| Failure::Input(format!("{name}: cannot read: {}", io_message(&e))))?;
    let Some(bytes) = bytes else {
        return Err(Failure::Input(format!(
            "{name}: larger than {} MiB, the largest scene file read",
            MAX_INPUT_BYTES >> 20
        )));
    };
    let mut text = String::from_utf8(bytes).map_err(|e| {
        Failure::Input(format!(
            "{name}: not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ))
    })?;
    // A byte-order mark is not part of the JSON document.
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    Ok(text)
}

/// `eigenray demo`: the air-over-water scene, a one-line summary and a picture.
fn demo(args: &DemoArgs) -> Result<(), Failure> {
    // The range check on `--receivers` keeps this conversion exact.
    let n = usize::try_from(args.receivers)
        .map_err(|_| Failure::Input("--receivers: too large".into()))?;
    let spec = eigenray::demo::air_water(n, args.seed);
    let scene = Scene::from_spec(&spec).map_err(Failure::scene)?;
    let tracer = Tracer::new(&scene).map_err(Failure::scene)?;
    // Start the worker threads first: the wall time is the solve's, not the pool's start-up.
    rayon::broadcast(|_| ());
    let start = Instant::now();
    let batch = trace(&tracer, true)?;
    let wall = start.elapsed().as_secs_f64();

    let index = |name: &str| scene.medium_index(name).map(|i| scene.media()[i].slowness);
    let media = match (index("air"), index("water")) {
        (Some(a), Some(w)) => format!("air over water (index {a:?} / {w:?})"),
        _ => "air over water".to_string(),
    };
    let mut summary = format!("demo: {media}, {}", batch_summary(&batch));
    if let Some((lo, hi)) = time_range(&batch) {
        let _ = write!(summary, "; time {lo:.2}..{hi:.2}");
    }
    let _ = write!(summary, "; {:.1} ms wall", wall * 1e3);
    if !batch.is_empty() {
        let _ = write!(summary, " ({:.2} µs/ray)", wall * 1e6 / batch.len() as f64);
    }

    let mut lines = vec![summary];
    if !args.no_svg {
        let title = format!(
            "eigenray demo: {media}, {} rays",
            svg::thousands(batch.len())
        );
        write_svg(&args.svg, &scene, &batch, &title, svg::Colouring::Time)?;
        lines.push(format!("wrote {}", args.svg.display()));
    }
    let mut out = io::stdout().lock();
    for line in lines {
        writeln!(out, "{line}").map_err(Failure::stdout)?;
    }
    out.flush().map_err(Failure::stdout)
}

/// `500 rays: 498 converged, 2 no_path` (statuses in the order of their `.npy` codes, zeros
/// left out).
fn batch_summary(batch: &Batch) -> String {
    let plural = if batch.len() == 1 { "ray" } else { "rays" };
    let head = format!("{} {plural}", batch.len());
    status_summary(head, batch.records().iter().map(|r| r.status))
}

/// `head: 3 converged, 1 vertex` over `statuses` (in the order of their `.npy` codes, zeros
/// left out; `head` alone when there are none).
fn status_summary(head: String, statuses: impl Iterator<Item = Status>) -> String {
    let mut counts = [0usize; 5];
    for status in statuses {
        if let Some(i) = eigenray::output::STATUS_CODES
            .iter()
            .position(|&s| s == status)
        {
            counts[i] += 1;
        }
    }
    let parts: Vec<String> = eigenray::output::STATUS_CODES
        .iter()
        .zip(counts)
        .filter(|(_, n)| *n > 0)
        .map(|(s, n)| format!("{n} {s}"))
        .collect();
    if parts.is_empty() {
        head
    } else {
        format!("{head}: {}", parts.join(", "))
    }
}

/// The picture's summary of what `solve` found: the batch's, or for every stationary path
/// `12 stationary paths of 5 rays: 10 converged, 2 vertex` (and the arrivals of a search).
fn solved_summary(solved: &Solved, arrivals: Option<&[SearchArrival]>) -> String {
    let mut summary = match solved {
        Solved::Batch(b) => batch_summary(b),
        Solved::Stationary(st) => {
            let (n, k) = (st.arrivals(), st.triples.len());
            let head = format!(
                "{n} stationary {} of {k} {}",
                if n == 1 { "path" } else { "paths" },
                if k == 1 { "ray" } else { "rays" }
            );
            let none = st
                .triples
                .iter()
                .filter(|t| t.arrivals.is_empty())
                .map(|t| {
                    if t.complete {
                        Status::NoPath
                    } else {
                        Status::NotConverged
                    }
                });
            let found = st
                .triples
                .iter()
                .flat_map(|t| &t.arrivals)
                .map(|a| a.status);
            status_summary(head, found.chain(none))
        }
    };
    if let Some(a) = arrivals {
        let _ = write!(
            summary,
            "; {} search {}",
            a.len(),
            if a.len() == 1 { "arrival" } else { "arrivals" }
        );
    }
    summary
}

/// Smallest and largest travel time of the rays that have one.
fn time_range(batch: &Batch) -> Option<(f64, f64)> {
    batch
        .records()
        .iter()
        .filter(|r| r.status.has_time() && r.time.is_finite())
        .fold(None, |acc, r| match acc {
            None => Some((r.time, r.time)),
            Some((lo, hi)) => Some((lo.min(r.time), hi.max(r.time))),
        })
}

/// Draws the picture and writes it to `path` (past [`svg::MAX_RAYS`] rays, a sample).
fn write_svg(
    path: &Path,
    scene: &Scene,
    batch: &Batch,
    title: &str,
    colouring: svg::Colouring,
) -> Result<(), Failure> {
    let svg = svg::scene_svg(scene, RaySet::Batch(batch), &[], title, colouring);
    fs::write(path, svg).map_err(|e| write_failure(path, &e))
}

/// A file that could not be written.
fn write_failure(path: &Path, e: &io::Error) -> Failure {
    Failure::Output(format!(
        "{}: cannot write: {}",
        path.display(),
        io_message(e)
    ))
}

/// Whether a write failed because the reader closed the pipe (also when the error comes
/// wrapped in a `serde_json` error, as `eigenray::write` returns it).
fn is_broken_pipe(e: &io::Error) -> bool {
    let inner = e
        .get_ref()
        .and_then(|i| i.downcast_ref::<serde_json::Error>())
        .and_then(serde_json::Error::io_error_kind);
    e.kind() == io::ErrorKind::BrokenPipe || inner == Some(io::ErrorKind::BrokenPipe)
}

/// The name of an input in messages.
fn display_name(path: &Path) -> String {
    if path.as_os_str() == "-" {
        "<stdin>".to_string()
    } else {
        path.display().to_string()
    }
}

/// An I/O error's description without the ` (os error N)` suffix.
fn io_message(e: &io::Error) -> String {
    let s = e.to_string();
    match s.rfind(" (os error ") {
        Some(i) if s.ends_with(')') => s[..i].to_string(),
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `solve` arguments of a command line.
    fn solve_args(args: &[&str]) -> SolveArgs {
        let cli = Cli::try_parse_from(["eigenray", "solve"].iter().chain(args)).unwrap();
        match cli.command {
            Some(Command::Solve(args)) => *args,
            other => panic!("{other:?}"),
        }
    }

    /// A scene with a `search` section and no rays (nothing goes to standard output).
    const SEARCH: &str = r#"{
        "media": { "air": { "speed": 1.0 } },
        "interfaces": { "floor": { "points": [[-3, 0], [3, 0]] } },
        "sources": [], "receivers": [[1, 1]],
        "search": { "max_steps": 1 }
    }"#;

    fn arrival(scene: &Scene) -> SearchArrival {
        SearchArrival {
            source: 0,
            receiver: 0,
            steps: vec![eigenray::scene::Step {
                kind: eigenray::scene::StepKind::Reflect,
                interface: 0,
            }],
            arrival: eigenray::Arrival {
                status: Status::Converged,
                time: 2.0,
                points: vec![
                    eigenray::Point::new(0.0, 1.0),
                    eigenray::Point::new(0.5, 0.0),
                    eigenray::Point::new(1.0, 1.0),
                ],
                parameters: vec![3.5],
                segments: vec![0],
                media: vec![scene.medium_index("air").unwrap(); 2],
                iterations: 1,
                reason: None,
                kink: None,
                residual: 0.0,
                amplitude: None,
                turns: None,
                caustics: None,
                launch_angle: None,
            },
            complete: true,
            heights: Vec::new(),
        }
    }

    #[test]
    fn csv_and_npy_need_a_file_for_the_arrivals() {
        // Refused before the solve: the arrivals would share the rays' one table.
        for format in ["csv", "npy"] {
            let args = solve_args(&["scene.json", "--format", format]);
            assert!(
                Destinations::of(&args).share_one_table(args.format),
                "{format}"
            );
            let args = solve_args(&["scene.json", "--format", format, "--arrivals", "a"]);
            assert!(
                !Destinations::of(&args).share_one_table(args.format),
                "{format}"
            );
            let args = solve_args(&["scene.json", "--format", format, "--ir", "h.npy"]);
            assert!(
                !Destinations::of(&args).share_one_table(args.format),
                "{format}"
            );
        }
        for format in ["json", "jsonl"] {
            let args = solve_args(&["scene.json", "--format", format]);
            assert!(
                !Destinations::of(&args).share_one_table(args.format),
                "{format}"
            );
        }
    }

    #[test]
    fn arrivals_go_to_their_own_file_in_the_chosen_format() {
        let scene = Scene::from_json(SEARCH).unwrap();
        let solved = Solved::Stationary(StationaryRays::default());
        let arrivals = [arrival(&scene)];
        let path = std::env::temp_dir().join(format!(
            "eigenray-main-test-{}-arrivals.csv",
            std::process::id()
        ));
        let path_text = path.to_string_lossy().into_owned();
        let args = solve_args(&["scene.json", "--format", "csv", "--arrivals", &path_text]);
        let written = write_outputs(&args, &scene, &solved, Some(&arrivals));
        let text = fs::read_to_string(&path);
        let _ = fs::remove_file(&path);
        assert!(written.is_ok(), "{written:?}");
        let text = text.unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 2, "{text}");
        assert!(lines[0].starts_with("source,receiver,steps,media,status"));
        assert!(
            lines[1].starts_with("0,0,reflect:floor,air;air,converged,,2.0,"),
            "{text}"
        );
    }
}
