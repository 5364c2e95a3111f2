//! The search's beam trees: every reflect-only sequence, one tree per source (in parallel)
//! shared by all its receivers, through [`MirrorWalls`] (`trace/mirrors.rs`, which walks the
//! geometry and validates each path as the classifier does). Every segment of each allowed
//! interface is a wall (none when reflections are not allowed: the tree is then its root, the
//! direct ray). Every leg is in the source's medium.

use rayon::prelude::*;

use crate::amplitude::{
    Amplitude, AxisymmetricRun, Incidence, LANES, NodeBounces, TreeLaws, UnfoldedLaws,
};
use crate::scene::SourceModel;
use crate::scene::{SearchOptions, Step, StepKind};
use crate::trace::{
    Arrival, GuidePath, MirrorPath, MirrorScratch, MirrorSearch, MirrorStats, MirrorWalls,
    RoomPath, Status, Tracer, TreeRun, Waveguide,
};

use super::{ArrivalCount, ArrivalSink, Control, SearchArrival, StreamedArrival};
use crate::options::Progress;

/// What one source's tree gives: its arrivals and what it did.
pub(super) struct SourceTree {
    /// Its arrivals (their `complete` is the caller's to set).
    pub arrivals: Vec<SearchArrival>,
    /// Beams, leaves, and whether it stopped short.
    pub stats: MirrorStats,
}

impl Tracer {
    /// The beam tree of every source, in parallel, in source order.
    pub(super) fn beam_trees(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
    ) -> Vec<SourceTree> {
        let scene = self.scene();
        let walls = if options.reflect {
            MirrorWalls::new(scene, &options.interfaces)
        } else {
            MirrorWalls::new(scene, &[])
        };
        // One source: its tree on this thread, without the parallel iterator (whose
        // splitter asks for the number of threads, and so starts the thread pool).
        if scene.sources().len() == 1 {
            let mut scratch = MirrorScratch::default();
            return vec![self.beam_tree(options, control, &walls, 0, &mut scratch)];
        }
        (0..scene.sources().len())
            .into_par_iter()
            .map_init(MirrorScratch::default, |scratch, source| {
                self.beam_tree(options, control, &walls, source, scratch)
            })
            .collect()
    }

    /// The beam tree of source `source`: its reflect-only arrivals (the direct ray included),
    /// `converged` ones and, when the search asks, `obstructed` ones.
    fn beam_tree(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
        walls: &MirrorWalls,
        source: usize,
        scratch: &mut MirrorScratch,
    ) -> SourceTree {
        let scene = self.scene();
        let s = scene.sources()[source];
        let mut arrivals = Vec::new();
        if !control.run.keep_going(Progress::default()) {
            return SourceTree {
                arrivals,
                stats: MirrorStats {
                    stopped: true,
                    ..MirrorStats::default()
                },
            };
        }
        // No medium at the source: no path at all (a proof).
        let Some(medium) = self.source_medium(false, s) else {
            return SourceTree {
                arrivals,
                stats: MirrorStats::default(),
            };
        };
        let search = MirrorSearch {
            scene,
            source: s,
            receivers: scene.receivers(),
            max_steps: options.step_limit(),
            max_time: options.time_limit(),
            slowness: scene.media()[medium].slowness,
            obstructed: options.obstructed,
            max_beams: control.run.limits.beams,
            max_depth: control.run.limits.depth,
            // The tree serves every receiver of its source: `solver.max_work` for each.
            max_work: scene
                .solver()
                .max_work
                .saturating_mul(scene.receivers().len().max(1) as u64),
        };
        let progress = &mut |beams| control.run.keep_going(Progress::work(beams));
        let stats = if let Some(paths) = control.paths {
            // Each path with its points to the caller's expansion (an extruded room's).
            walls.arrivals(
                &search,
                scratch,
                &mut |p: MirrorPath<'_>| paths(beam_arrival(walls, source, medium, p)),
                progress,
            )
        } else if let Some(sink) = control.sink
            && let Some(guide) = walls.waveguide(&search)
            && let Some(unfolded) = self.unfolded(walls, guide, &search, medium)
        {
            // Streamed between two parallel walls: each image's time and amplitude in closed
            // form, no points (`trace/mirrors/waveguide.rs`).
            let guided = Guided {
                walls,
                guide,
                search: &search,
                source,
                medium,
            };
            self.stream_waveguide(&guided, unfolded, control, sink, progress)
        } else if let Some(sink) = control.sink {
            // Streamed: each path's amplitude from its points, in buffers reused path to path.
            let mut path = StreamScratch::default();
            let found = &mut |p: MirrorPath<'_>| {
                control.listed.stream();
                sink.arrival(path.arrival(self, walls, source, medium, p));
                true
            };
            // In a rectangular room, the image paths in closed form where the amplitude has
            // one (or the scene asks for none).
            let laws = walls.room_walls(&search).map(|room| {
                let places = room.map(|w| {
                    let place = walls.place(w);
                    (place.interface, place.segment)
                });
                self.unfolded_laws(medium, places, s)
            });
            match laws {
                Some(laws) if laws.is_some() || scene.amplitudes().is_none() => {
                    let unfolded = &mut |u: &RoomPath| {
                        control.listed.stream();
                        let amplitude = laws.as_ref().and_then(|laws| {
                            let reflections = u.walls.map(|(_, n)| n);
                            // The x walls at one angle, the y walls at the other.
                            let [x, y] = u.cos;
                            let on_x = Incidence {
                                cos: x,
                                sin2: y * y,
                            };
                            let on_y = Incidence {
                                cos: y,
                                sin2: x * x,
                            };
                            let incidence = [on_x, on_x, on_y, on_y];
                            laws.amplitude(reflections, incidence, u.length, None, false)
                        });
                        sink.arrival(StreamedArrival {
                            source,
                            receiver: u.receiver,
                            steps: u.steps,
                            diffractions: 0,
                            vertical_reflections: 0,
                            status: Status::Converged,
                            time: u.time,
                            amplitude,
                        });
                        true
                    };
                    walls.arrivals_unfolded(&search, scratch, found, unfolded, progress)
                }
                _ => self.stream_tree(
                    walls, &search, source, medium, control, sink, scratch, found, progress,
                ),
            }
        } else {
            walls.arrivals(
                &search,
                scratch,
                &mut |p: MirrorPath<'_>| {
                    if !control.listed.take(p.walls.len()) {
                        return false;
                    }
                    arrivals.push(beam_arrival(walls, source, medium, p));
                    true
                },
                progress,
            )
        };
        SourceTree { arrivals, stats }
    }
}

impl Tracer {
    /// The streamed arrivals of one source between two parallel walls, each image's time and
    /// amplitude in closed form (`unfolded`; `None` in a scene without amplitudes), a bounce
    /// near a critical angle through the tree's own path, walked.
    fn stream_waveguide(
        &self,
        g: &Guided<'_>,
        unfolded: Option<UnfoldedLaws<'_, 2>>,
        control: &Control<'_>,
        sink: &dyn ArrivalSink,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let source_x = g.search.source.x;
        let receivers = g.search.receivers;
        let mut path = StreamScratch::default();
        let mut walked = MirrorScratch::default();
        let mut batch = SinkBatch::new(sink, control.listed);
        g.walls.guide_arrivals(
            g.guide,
            g.search,
            &mut |p: GuidePath| {
                let amplitude = unfolded.and_then(|u| {
                    let x = receivers[p.receiver].x;
                    let width = Some(x.abs() * p.length / (x - source_x).abs());
                    let along = p.along / p.length;
                    let incidence = Incidence {
                        cos: p.across / p.length,
                        sin2: along * along,
                    };
                    let hits = p.hits.map(|n| n as u64);
                    let closed =
                        |checked| u.amplitude(hits, [incidence; 2], p.length, width, checked);
                    closed(true).or_else(|| {
                        // Ill-conditioned in closed form: the tree's path, walked.
                        match g.walls.guide_path(g.guide, g.search, &p, &mut walked) {
                            Some(tree) => {
                                path.arrival(self, g.walls, g.source, g.medium, tree)
                                    .amplitude
                            }
                            None => closed(false),
                        }
                    })
                });
                batch.push(StreamedArrival {
                    source: g.source,
                    receiver: p.receiver,
                    steps: p.hits[0] + p.hits[1],
                    diffractions: 0,
                    vertical_reflections: 0,
                    status: Status::Converged,
                    time: p.time,
                    amplitude,
                });
                true
            },
            progress,
        )
    }

    /// Whether a streamed search of one source (`search`, in medium `medium`) may take the
    /// waveguide's closed forms: `Some(None)` in a scene without amplitudes (times only),
    /// `Some(Some(form))` with the amplitudes' form, `None` where some path needs its
    /// points (a scene with a gradient medium; an axisymmetric scene whose walls are not
    /// horizontal, or with a receiver on the axis; a `"media"` wall whose medium across is
    /// not one along it).
    fn unfolded(
        &self,
        walls: &MirrorWalls,
        guide: &Waveguide,
        search: &MirrorSearch<'_>,
        medium: usize,
    ) -> Option<Option<UnfoldedLaws<'_, 2>>> {
        let scene = self.scene();
        if scene.curved() {
            return None;
        }
        let Some(settings) = scene.amplitudes() else {
            return Some(None);
        };
        if settings.source == SourceModel::Axisymmetric {
            let (u, _) = guide.axes();
            let off_axis = |x: f64| x != 0.0 && x.is_finite();
            if u.y != 0.0
                || search.source.x != 0.0
                || !search.receivers.iter().all(|r| off_axis(r.x))
            {
                return None;
            }
        }
        let places = guide.walls().map(|w| {
            let place = walls.place(w);
            (place.interface, place.segment)
        });
        let regions = self.regions();
        UnfoldedLaws::new(scene, settings, regions, medium, places, search.source).map(Some)
    }
}

impl Tracer {
    /// The streamed tree of one source (`search`, in medium `medium`): the certain beams'
    /// paths in closed form (`trace/mirrors/grid.rs`) where the laws allow it, each other
    /// path to `found`.
    #[expect(
        clippy::too_many_arguments,
        reason = "the search, its source, its sink, its scratch and its callbacks"
    )]
    fn stream_tree(
        &self,
        walls: &MirrorWalls,
        search: &MirrorSearch<'_>,
        source: usize,
        medium: usize,
        control: &Control<'_>,
        sink: &dyn ArrivalSink,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let scene = self.scene();
        let Some(laws) = self.tree_laws(walls, search, medium) else {
            return walls.arrivals(search, scratch, found, progress);
        };
        let tree = TreeStream {
            source,
            search,
            laws: laws.as_ref(),
            axisymmetric: scene
                .amplitudes()
                .is_some_and(|a| a.source == SourceModel::Axisymmetric),
            arch: pulp::Arch::new(),
        };
        let angled: Vec<bool> = (0..scene.interfaces().len())
            .map(|i| laws.as_ref().is_some_and(|l| l.angled(i)))
            .collect();
        let mut batch = SinkBatch::new(sink, control.listed);
        let (mut node, mut prepared) = (NodeBounces::default(), None);
        let unfolded = &mut |run: &TreeRun<'_>| {
            if prepared != Some(run.node) {
                if let Some(laws) = tree.laws {
                    laws.prepare(run.groups, &mut node);
                }
                prepared = Some(run.node);
            }
            tree.take(run, &node, &mut batch)
        };
        walls.arrivals_streamed(search, scratch, &angled, found, unfolded, progress)
    }
}

impl Tracer {
    /// The laws of a streamed tree's closed forms (`trace/mirrors/grid.rs`) for one source
    /// (`search`, in medium `medium`): `Some(None)` in a scene without amplitudes (times
    /// only), `Some(Some(laws))` with them, `None` where some path needs its points (a
    /// scene with a gradient medium; a `"media"` wall whose medium across is not one along
    /// its interface).
    fn tree_laws(
        &self,
        walls: &MirrorWalls,
        search: &MirrorSearch<'_>,
        medium: usize,
    ) -> Option<Option<TreeLaws<'_>>> {
        let scene = self.scene();
        if scene.curved() {
            return None;
        }
        let Some(settings) = scene.amplitudes() else {
            return Some(None);
        };
        let places: Vec<(usize, usize)> = (0..walls.count())
            .map(|w| {
                let place = walls.place(w);
                (place.interface, place.segment)
            })
            .collect();
        let regions = self.regions();
        TreeLaws::new(scene, settings, regions, medium, &places, search.source).map(Some)
    }
}

/// One source's streamed tree in closed form: its index, its search, the laws (`None`: no
/// amplitudes), and whether the source is axisymmetric.
struct TreeStream<'a> {
    source: usize,
    search: &'a MirrorSearch<'a>,
    laws: Option<&'a TreeLaws<'a>>,
    axisymmetric: bool,
    /// The processor's vector instructions ([`take`](Self::take)).
    arch: pulp::Arch,
}

impl TreeStream<'_> {
    /// The arrivals of `run` with their amplitudes in closed form into `batch`, in order,
    /// up to the first whose closed form declines (a bounce near a critical angle; for an
    /// axisymmetric source, a source off the axis or a path not certainly on one side of
    /// it), which the caller walks: how many it took. `node`: the bounces of the run's node,
    /// prepared (once a node). The amplitudes [`LANES`] at a time
    /// ([`TreeLaws::node_amplitudes`]).
    #[inline]
    fn take(&self, run: &TreeRun<'_>, node: &NodeBounces, batch: &mut SinkBatch<'_>) -> usize {
        // Compiled for the processor's vector instructions where it has them (AVX2,
        // AVX-512): the same operations on each path, so the same numbers (Rust contracts
        // no multiply-adds).
        self.arch.dispatch(TakeRun {
            tree: self,
            run,
            node,
            batch,
        })
    }

    /// [`take`](Self::take)'s work.
    #[inline(always)]
    fn take_compiled(
        &self,
        run: &TreeRun<'_>,
        node: &NodeBounces,
        batch: &mut SinkBatch<'_>,
    ) -> usize {
        let n = run.receivers.len();
        let arrival = |k: usize, amplitude: Option<Amplitude>| StreamedArrival {
            source: self.source,
            receiver: run.receivers[k],
            steps: run.steps,
            diffractions: 0,
            vertical_reflections: 0,
            status: Status::Converged,
            time: run.times[k],
            amplitude,
        };
        let Some(laws) = self.laws else {
            for k in 0..n {
                batch.push(arrival(k, None));
            }
            return n;
        };
        if self.axisymmetric && self.search.source.x != 0.0 {
            return 0;
        }
        let mut start = 0;
        while start < n {
            let full = (start + LANES).min(n);
            let mut end = full;
            let mut widths = [AxisymmetricRun {
                receiver_x: 0.0,
                along: 0.0,
            }; LANES];
            if self.axisymmetric {
                for k in start..full {
                    let Some(along) = run.axisymmetric_run(k) else {
                        end = k;
                        break;
                    };
                    widths[k - start] = AxisymmetricRun {
                        receiver_x: self.search.receivers[run.receivers[k]].x.abs(),
                        along,
                    };
                }
            }
            let lanes = start..end;
            let declined = laws.node_amplitudes(
                node,
                &run.directions[lanes.clone()],
                &run.lengths[lanes.clone()],
                self.axisymmetric.then_some(&widths[..lanes.len()]),
                |k, amplitude| batch.push(arrival(start + k, Some(amplitude))),
            );
            if let Some(k) = declined {
                return start + k;
            }
            if end < full {
                return end;
            }
            start = end;
        }
        n
    }
}

/// [`TreeStream::take`]'s work, as [`pulp::Arch::dispatch`] compiles it for each set of
/// vector instructions (everything it calls inlined, so compiled with them).
struct TakeRun<'t, 'r, 'b, 's> {
    tree: &'t TreeStream<'t>,
    run: &'r TreeRun<'r>,
    node: &'r NodeBounces,
    batch: &'b mut SinkBatch<'s>,
}

impl pulp::WithSimd for TakeRun<'_, '_, '_, '_> {
    type Output = usize;

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) -> usize {
        self.tree.take_compiled(self.run, self.node, self.batch)
    }
}

/// How many arrivals in closed form a [`SinkBatch`] holds before it hands them on.
const SINK_BATCH: usize = 256;

/// Arrivals in closed form on their way to the sink, handed on (and counted) a batch at a
/// time, in the order found; the rest when it is dropped.
struct SinkBatch<'a> {
    sink: &'a dyn ArrivalSink,
    listed: &'a ArrivalCount,
    held: Vec<StreamedArrival>,
}

impl<'a> SinkBatch<'a> {
    fn new(sink: &'a dyn ArrivalSink, listed: &'a ArrivalCount) -> SinkBatch<'a> {
        SinkBatch {
            sink,
            listed,
            held: Vec::with_capacity(SINK_BATCH),
        }
    }

    #[inline]
    fn push(&mut self, arrival: StreamedArrival) {
        self.held.push(arrival);
        if self.held.len() >= SINK_BATCH {
            self.flush();
        }
    }

    fn flush(&mut self) {
        if !self.held.is_empty() {
            self.listed.stream_many(self.held.len());
            self.sink.arrivals(&self.held);
            self.held.clear();
        }
    }
}

impl Drop for SinkBatch<'_> {
    fn drop(&mut self) {
        self.flush();
    }
}

/// One source's search between two parallel walls: the walls, the waveguide they form, the
/// search, the source and its medium.
struct Guided<'a> {
    walls: &'a MirrorWalls,
    guide: &'a Waveguide,
    search: &'a MirrorSearch<'a>,
    source: usize,
    medium: usize,
}

/// A path of the beam tree as a [`SearchArrival`]: its walls' steps, segments and arclengths,
/// every leg in the source's medium.
pub(super) fn beam_arrival(
    walls: &MirrorWalls,
    source: usize,
    medium: usize,
    p: MirrorPath<'_>,
) -> SearchArrival {
    let k = p.walls.len();
    let mut steps = Vec::with_capacity(k);
    let mut segments = Vec::with_capacity(k);
    let mut parameters = Vec::with_capacity(k);
    for (&w, &point) in p.walls.iter().zip(&p.points[1..=k]) {
        let place = walls.place(w);
        steps.push(Step {
            kind: StepKind::Reflect,
            interface: place.interface,
        });
        segments.push(place.segment);
        parameters.push(place.start + place.p.distance(point));
    }
    SearchArrival {
        source,
        receiver: p.receiver,
        steps,
        arrival: Arrival {
            status: p.status,
            time: p.time,
            points: p.points.to_vec(),
            parameters,
            segments,
            media: vec![medium; k + 1],
            iterations: 0,
            reason: p.reason,
            kink: None,
            // The image method's points: no solve, no residual.
            residual: f64::NAN,
            amplitude: None,
            turns: None,
            caustics: None,
            launch_angle: None,
        },
        complete: true,
        heights: Vec::new(),
    }
}

/// The steps, segments and leg media of one streamed path of the beam tree, reused path to
/// path.
#[derive(Default)]
struct StreamScratch {
    steps: Vec<Step>,
    segments: Vec<usize>,
    media: Vec<usize>,
}

impl StreamScratch {
    /// A path of the beam tree as the sink sees it, with the amplitude
    /// [`Tracer::search`] gives its [`SearchArrival`] (the same steps, segments and media).
    fn arrival(
        &mut self,
        tracer: &Tracer,
        walls: &MirrorWalls,
        source: usize,
        medium: usize,
        p: MirrorPath<'_>,
    ) -> StreamedArrival {
        let k = p.walls.len();
        let amplitude = if tracer.scene().amplitudes().is_some() {
            self.steps.clear();
            self.segments.clear();
            for &w in p.walls {
                let place = walls.place(w);
                self.steps.push(Step {
                    kind: StepKind::Reflect,
                    interface: place.interface,
                });
                self.segments.push(place.segment);
            }
            self.media.clear();
            self.media.resize(k + 1, medium);
            let segments = Some(&self.segments[..]);
            tracer.amplitude_with(&self.steps, p.status, p.points, &self.media, segments)
        } else {
            None
        };
        StreamedArrival {
            source,
            receiver: p.receiver,
            steps: k,
            diffractions: 0,
            vertical_reflections: 0,
            status: p.status,
            time: p.time,
            amplitude,
        }
    }
}
