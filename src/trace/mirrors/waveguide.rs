//! Two parallel walls (a waveguide): the arrivals of a streamed search from the image
//! lattice, without a path's points.
//!
//! When the scene's only interfaces are two straight walls, parallel (in any orientation),
//! both reflecting, and the source and every receiver lie strictly between their lines and
//! strictly within the stretch both walls span, every image of the source lies on a 1-D
//! lattice across the walls: image `j` (any integer) is at local coordinates
//! `(x, j H + (y or H − y))` (by the parity of `j`; `H` the walls' distance, `(x, y)` the
//! source's), with `|j|` reflections, alternating between the two walls. The straight line
//! from an image to a receiver is the unfolded path: every reflection point lies between the
//! source and the receiver along the walls, so within the walls, and no leg can cross an
//! interface (there is none but the two walls). So every image is a path, with no validation:
//! its time is the slowness times the image's distance from the receiver, and every bounce on
//! one wall meets it at one angle (the unfolded line's), so its amplitude has a closed form
//! (`amplitude::ray::of_unfolded`).
//!
//! This serves [`Tracer::search_into`](crate::Tracer::search_into) only, whose arrivals carry
//! no points; the listed search (`search`, with points) still takes the beam tree, whose
//! arithmetic gives the points. The two agree on the arrivals (the same sequences to the
//! same receivers) and on their times and amplitudes to round-off (this module's tests).
//! The limits are the lattice's of a room (`mirrors/shoebox.rs`): an image is a beam and one
//! unit of work (it costs the same at any depth: no leg is walked), `max_steps`, the depth
//! limit, `max_time`, the beams and work limits, and the run's stop (polled every
//! [`POLL_WORK`] images).

use crate::geom::{Point, Vec2};
use crate::scene::Scene;

use super::{
    Bounds, MirrorPath, MirrorScratch, MirrorSearch, MirrorStats, MirrorWalls, Node,
    PROGRESS_BEAMS, Status, Validation, Wall,
};

/// The largest deviation from parallel walls (the second wall's ends' heights over the
/// first's line may differ by this, relative to the walls' size) that is taken for a
/// waveguide: the lattice's images then lie within round-off of the tree's at the depths a
/// search walks.
const PARALLEL_TOLERANCE: f64 = 1e-14;

/// Images listed between two polls of the run for a stop request.
const POLL_WORK: u64 = 1 << 14;

/// Two parallel walls: the first's line is local `y = 0`, the second's `y = h`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Waveguide {
    /// The first wall's start: local (0, 0).
    c0: Point,
    /// The unit vector along the walls, and across them (towards the second wall).
    u: Vec2,
    v: Vec2,
    /// The distance between the walls' lines.
    h: f64,
    /// The walls (indices into [`MirrorWalls`]) on the lines `y = 0` and `y = h`.
    walls: [usize; 2],
    /// The stretch of local `x` both walls span.
    span: [f64; 2],
}

/// One arrival of a waveguide, as a streamed search needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GuidePath {
    /// The receiver's index in the receivers given.
    pub receiver: usize,
    /// Reflections on the wall at `y = 0`, and on the wall at `y = h`.
    pub hits: [usize; 2],
    /// Which of the two walls the path reflects off first (0 or 1; none for the direct path).
    pub first: usize,
    /// The unfolded path's length, and its components along the walls and across them
    /// (both as magnitudes).
    pub length: f64,
    pub along: f64,
    pub across: f64,
    /// The travel time: the slowness times the length.
    pub time: f64,
}

impl Waveguide {
    /// The waveguide the walls form, when they are every segment of the scene (two) and
    /// parallel within [`PARALLEL_TOLERANCE`], on distinct lines.
    pub(super) fn of(scene: &Scene, walls: &[Wall]) -> Option<Waveguide> {
        let segments: usize = scene
            .interfaces()
            .iter()
            .map(|i| i.polyline.num_segments())
            .sum();
        if walls.len() != 2 || segments != 2 {
            return None;
        }
        let (a, b) = (&walls[0], &walls[1]);
        let (la, lb) = (a.e.length(), b.e.length());
        if !(la > 0.0 && lb > 0.0 && la.is_finite() && lb.is_finite()) {
            return None;
        }
        let u = a.e * (1.0 / la);
        let n = u.perp();
        let (hp, hq) = (n.dot(b.p - a.p), n.dot(b.q - a.p));
        let size = la + lb + hp.abs();
        if !(hp.is_finite() && hq.is_finite())
            || hp == 0.0
            || hq == 0.0
            || hp.signum() != hq.signum()
            || (hp - hq).abs() > PARALLEL_TOLERANCE * size
        {
            return None;
        }
        let h = 0.5 * (hp + hq);
        let v = if h > 0.0 { n } else { -n };
        let h = h.abs();
        let (bp, bq) = (u.dot(b.p - a.p), u.dot(b.q - a.p));
        let span = [bp.min(bq).max(0.0), bp.max(bq).min(la)];
        (span[0] < span[1]).then_some(Waveguide {
            c0: a.p,
            u,
            v,
            h,
            walls: [0, 1],
            span,
        })
    }

    /// `x` in the waveguide's local coordinates.
    #[inline(always)]
    fn local(&self, x: Point) -> (f64, f64) {
        let d = x - self.c0;
        (d.dot(self.u), d.dot(self.v))
    }

    /// Whether `x` lies between the walls and within the stretch both span, farther than
    /// the lattice's margin from their lines and ends.
    fn inside(&self, x: Point) -> bool {
        let (lx, ly) = self.local(x);
        let g = 1e-9 * (self.h + self.span[1] - self.span[0]);
        ly > g && ly < self.h - g && lx > self.span[0] + g && lx < self.span[1] - g
    }

    /// Whether the lattice serves `search`: its source and every receiver inside, no
    /// receiver at the source.
    pub(super) fn serves(&self, search: &MirrorSearch<'_>) -> bool {
        self.inside(search.source)
            && search
                .receivers
                .iter()
                .all(|&r| r != search.source && self.inside(r))
    }

    /// The walls (indices into [`MirrorWalls`]) on the lines `y = 0` and `y = h`.
    pub(crate) fn walls(&self) -> [usize; 2] {
        self.walls
    }

    /// The unit vector along the walls and the one across them (towards the wall at `y = h`).
    pub(crate) fn axes(&self) -> (Vec2, Vec2) {
        (self.u, self.v)
    }
}

/// The local `y` of image `j` of a source at local `y`, between lines `0` and `h`.
#[inline(always)]
fn image(j: i64, h: f64, y: f64) -> f64 {
    j as f64 * h + if j.rem_euclid(2) == 0 { y } else { h - y }
}

/// The search's state while it lists a waveguide's images.
struct Lister<'a, 'b, 's, F, P> {
    search: &'a MirrorSearch<'s>,
    found: &'b mut F,
    progress: &'b mut P,
    stats: MirrorStats,
    granted: u64,
    /// The work done since the last poll of `progress`.
    unpolled: u64,
}

impl<F, P> Lister<'_, '_, '_, F, P>
where
    F: FnMut(GuidePath) -> bool,
    P: FnMut(u64) -> bool,
{
    /// One more image of `k` reflections: `false` where a limit or the run stops the search.
    fn image(&mut self, k: usize) -> bool {
        if k > 0 {
            self.stats.beams += 1;
            if self.stats.beams > self.granted {
                if !(self.progress)(PROGRESS_BEAMS) {
                    self.stats.beams -= 1;
                    self.stats.stopped = true;
                    return false;
                }
                self.granted += PROGRESS_BEAMS;
            }
            if self.stats.beams > self.search.max_beams {
                self.stats.beams -= 1;
                self.stats.stopped = true;
                return false;
            }
        }
        // One unit of work an image: its time and amplitude cost the same at any depth.
        self.stats.leaves += 1;
        self.stats.work += 1;
        if self.stats.work > self.search.max_work {
            self.stats.stopped = true;
            return false;
        }
        self.unpolled += 1;
        if self.unpolled >= POLL_WORK {
            self.unpolled = 0;
            if !(self.progress)(0) {
                self.stats.stopped = true;
                return false;
            }
        }
        true
    }
}

impl MirrorWalls {
    /// The waveguide of the walls when it serves `search` (see `mirrors/waveguide.rs`).
    pub(crate) fn waveguide(&self, search: &MirrorSearch<'_>) -> Option<&Waveguide> {
        self.waveguide.as_ref().filter(|g| g.serves(search))
    }

    /// The arrivals of `search` in the waveguide `guide` (which serves it): per receiver, the
    /// direct path, then the images beyond the wall at `y = h` and then those beyond the
    /// wall at `y = 0`, each side nearest first; each reported to `found` (which returns
    /// `false` to stop the search). The same paths as [`MirrorWalls::arrivals`] (the same
    /// sequences to the same receivers, times to round-off); `progress` as there.
    pub(crate) fn guide_arrivals(
        &self,
        guide: &Waveguide,
        search: &MirrorSearch<'_>,
        found: &mut impl FnMut(GuidePath) -> bool,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let max_steps = search.max_steps.min(search.max_depth);
        let bounds: Bounds = self.bounds(search, max_steps);
        let mut lister = Lister {
            search,
            found,
            progress,
            stats: MirrorStats::default(),
            granted: 0,
            unpolled: 0,
        };
        if bounds.late(search.source, None) {
            return lister.stats;
        }
        let medium = search.medium();
        // One deeper than walked where the depth limit cuts `max_steps`, to tell.
        let deeper = usize::from(search.max_steps > max_steps);
        let n = (max_steps + deeper).min(i64::MAX as usize / 4) as i64;
        // The images within reach, with a margin far above the distances' round-off (each
        // path's own time then decides).
        let reach = bounds.reach * (1.0 + 1e-9) + 4.0 * bounds.delta;
        let h = guide.h;
        let (sx, sy) = guide.local(search.source);
        for (r, &receiver) in search.receivers.iter().enumerate() {
            let (rx, ry) = guide.local(receiver);
            let dx = rx - sx;
            let along = dx.abs();
            for side in [1i64, -1] {
                // The direct path (j = 0) once, with the images beyond `y = h`.
                for k in i64::from(side < 0)..=n {
                    let j = side * k;
                    let dy = image(j, h, sy) - ry;
                    let length = crate::leg::length(Vec2::new(dx, dy));
                    if length > reach {
                        break;
                    }
                    let k = k as usize;
                    if k > max_steps {
                        // The depth limit, beyond which paths may remain.
                        lister.stats.stopped = true;
                        break;
                    }
                    let time = medium.time_along(length);
                    if time > search.max_time {
                        break;
                    }
                    if !lister.image(k) {
                        return lister.stats;
                    }
                    // Lines `m h` crossed: m = j..1 (j > 0) or j+1..0 (j < 0); line `m h`
                    // is the wall at y = 0 for even m. The first crossed is the first
                    // reflection.
                    let (high, first_line) = if j > 0 {
                        (k.div_ceil(2), j)
                    } else {
                        (k / 2, j + 1)
                    };
                    let path = GuidePath {
                        receiver: r,
                        hits: [k - high, high],
                        first: first_line.rem_euclid(2) as usize,
                        length,
                        along,
                        across: dy.abs(),
                        time,
                    };
                    if !(lister.found)(path) {
                        // The caller's stop: the list is short.
                        lister.stats.stopped = true;
                        return lister.stats;
                    }
                }
            }
        }
        lister.stats
    }

    /// The beam tree's own path of `path` (an arrival [`MirrorWalls::guide_arrivals`]
    /// reported for `search`): its walls, its points and time by the tree's arithmetic (the
    /// images by successive mirroring, the points by [`Validation::path`]), bit for bit what
    /// the tree lists, for an amplitude whose closed form is ill-conditioned (a bounce at the
    /// critical angle). `None` where the tree would not list it (never, to round-off).
    pub(crate) fn guide_path<'s>(
        &self,
        guide: &Waveguide,
        search: &MirrorSearch<'_>,
        path: &GuidePath,
        scratch: &'s mut MirrorScratch,
    ) -> Option<MirrorPath<'s>> {
        let MirrorScratch {
            stack,
            walls: sequence,
            points,
            rel,
            lens,
            far,
            ..
        } = scratch;
        let k = path.hits[0] + path.hits[1];
        sequence.clear();
        sequence.extend((0..k).map(|i| guide.walls[(path.first + i) % 2]));
        stack.clear();
        stack.push(Node {
            wall: usize::MAX,
            image: search.source,
            beam: None,
            next: 0,
        });
        let mut image = search.source;
        for &w in sequence.iter() {
            image = self.walls[w].mirror(image);
            stack.push(Node {
                wall: w,
                image,
                beam: None,
                next: 0,
            });
        }
        let mut validation = Validation {
            search,
            walls: &self.walls,
            points,
            rel,
            lens,
            far,
            crossings: false,
            crossers: None,
        };
        let receiver = search.receivers[path.receiver];
        let (length, _) = validation.path(stack, receiver)?;
        Some(MirrorPath {
            receiver: path.receiver,
            walls: sequence,
            points,
            time: search.medium().time_along(length),
            status: Status::Converged,
            reason: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Walls `a` and `b` (each one interface of one segment) and `more` interfaces, in air.
    fn scene(a: [[f64; 2]; 2], b: [[f64; 2]; 2], more: &str) -> Scene {
        Scene::from_json(&format!(
            r#"{{ "media": {{ "air": {{ "speed": 343.0 }} }}, "background": "air",
                "interfaces": {{ "a": {{ "points": {a:?} }}, "b": {{ "points": {b:?} }} {more} }},
                "sources": [[1, 1]], "receivers": [[2, 1]], "paths": [{{ "steps": [] }}] }}"#
        ))
        .unwrap()
    }

    fn search<'a>(scene: &'a Scene, source: Point, receivers: &'a [Point]) -> MirrorSearch<'a> {
        MirrorSearch {
            scene,
            source,
            receivers,
            max_steps: 10,
            max_depth: crate::scene::MAX_SEARCH_STEPS,
            max_time: f64::INFINITY,
            slowness: 1.0 / 343.0,
            obstructed: false,
            max_beams: u64::MAX,
            max_work: u64::MAX,
        }
    }

    /// Parallel walls either way round, of different stretches: a waveguide over the
    /// stretch both span; not parallel (by 1e-9), a third interface, one wall not
    /// reflecting, or both on one line: none.
    #[test]
    fn only_two_parallel_walls_are_a_waveguide() {
        let guide = |s: &Scene, reflecting: &[usize]| MirrorWalls::new(s, reflecting).waveguide;
        let s = scene([[10.0, 3.0], [-5.0, 3.0]], [[0.0, 0.0], [20.0, 0.0]], "");
        let g = guide(&s, &[0, 1]).expect("a waveguide");
        assert_eq!(g.h, 3.0);
        // The stretch both span: x from 0 to 10, whichever way round.
        let r = [Point::new(9.0, 2.0)];
        assert!(g.serves(&search(&s, Point::new(0.5, 1.0), &r)));
        let beyond = [Point::new(11.0, 2.0)];
        assert!(!g.serves(&search(&s, Point::new(0.5, 1.0), &beyond)));
        let outside = [Point::new(5.0, 3.5)];
        assert!(!g.serves(&search(&s, Point::new(0.5, 1.0), &outside)));
        let at_source = [Point::new(0.5, 1.0)];
        assert!(!g.serves(&search(&s, Point::new(0.5, 1.0), &at_source)));
        let tilted = scene(
            [[0.0, 0.0], [20.0, 0.0]],
            [[0.0, 3.0], [20.0, 3.0 + 1e-9]],
            "",
        );
        assert!(guide(&tilted, &[0, 1]).is_none());
        let third = r#", "c": { "points": [[30, -1], [30, 4]] }"#;
        let three = scene([[0.0, 0.0], [20.0, 0.0]], [[0.0, 3.0], [20.0, 3.0]], third);
        assert!(guide(&three, &[0, 1]).is_none());
        assert!(guide(&s, &[0]).is_none());
        let collinear = scene([[0.0, 0.0], [5.0, 0.0]], [[6.0, 0.0], [20.0, 0.0]], "");
        assert!(guide(&collinear, &[0, 1]).is_none());
    }
}
