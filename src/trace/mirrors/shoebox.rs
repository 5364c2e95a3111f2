//! A rectangular room (a "shoebox"): the beam tree's arrivals from the image lattice.
//!
//! When the scene's only interfaces are four walls forming a rectangle (in any orientation),
//! all of them reflecting, and the source and every receiver lie strictly inside it, every
//! image of the source lies on a lattice: image `(i, j)` is at local coordinates
//! `(i L₁ + (x or L₁ − x), j L₂ + (y or L₂ − y))` (by the parity of `i` and `j`), it has
//! `|i| + |j|` reflections, and the straight line from it to a receiver inside the room
//! crosses the lattice's lines in the order of the path's reflections (the unfolded path).
//! Every such path is valid (a chord of a convex room between points of different walls
//! touches no other wall), except where it passes a corner. So instead of the tree's beams
//! (whose number grows like the cube of the depth in a rectangle, the images only like its
//! square), the images within reach of each receiver are listed directly, and each one's
//! sequence of walls is read off the lattice lines its line crosses.
//!
//! Each listed sequence is then taken through the tree's own arithmetic: its images by
//! successive mirroring in the scene's walls ([`Wall::mirror`], as the tree's nodes hold
//! them) and its points, sides and vanished legs by the tree's validation
//! ([`Validation::path`]), so that its points and time are the tree's to the bit. Only the
//! crossing test (no leg may cross an interface) is left out, since no leg of a valid
//! sequence in a convex room can cross one.
//!
//! **Where the lattice is not certain.** The scene's rectangle is one only to round-off (a
//! rotated rectangle's corners are rounded), so the scene's images differ from the lattice's
//! by at most `e(k)`, which grows like `k²` times the rectangle's deviation (and its
//! round-off) with the number `k` of reflections. Where the line from a lattice image passes
//! within `e(k)` (divided by the sine of its angle to the lattice lines) of a lattice corner,
//! the order of the two reflections there is not certain, nor whether the path exists:
//! every order of such near-tied crossings is then tried with the tree's whole validation,
//! the crossing test included. Above [`MAX_ORDERS`] orders for one image the search says it
//! stopped (its list may be short), rather than guess.

use crate::geom::{Point, Vec2};
use crate::scene::Scene;

use super::{
    Bounds, MirrorPath, MirrorScratch, MirrorSearch, MirrorStats, MirrorWalls, Node,
    PROGRESS_BEAMS, Status, Validation, Wall,
};

/// The largest relative deviation from a rectangle (of the angle at a corner, and of the
/// fourth corner from where the other three put it, per the sum of the sides) that is taken
/// for a rectangle.
const RECTANGLE_TOLERANCE: f64 = 1e-12;

/// The most orders of near-tied crossings tried for one image.
const MAX_ORDERS: usize = 64;

/// Work (reflections of the paths validated) between two polls of the run for a stop
/// request: an image of `k` reflections costs `k`, and a deep search's images cost thousands
/// each, so a block of [`PROGRESS_BEAMS`] images alone would poll too seldom.
const POLL_WORK: u64 = 1 << 16;

/// A rectangle of four walls: its corner `c0`, its unit axes and side lengths, and which wall
/// lies on which side.
#[derive(Clone, Copy, Debug)]
pub(super) struct Shoebox {
    /// The corner where the local coordinates are (0, 0).
    c0: Point,
    /// Unit vectors along the sides from `c0` (lengths `l1` and `l2`).
    u: Vec2,
    v: Vec2,
    l1: f64,
    l2: f64,
    /// The walls (indices into [`MirrorWalls`]) on the local lines x = 0, x = L₁, y = 0, y = L₂.
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
    /// The deviation of the lattice per unit length and squared depth: the rectangle's own
    /// deviation and the round-off of successive mirrorings.
    deviation: f64,
    /// The rectangle's own deviation (of the angle at a corner and of the fourth corner,
    /// without the round-off of mirroring): 0 for axis-aligned walls.
    shape: f64,
}

impl Shoebox {
    /// The rectangle the walls form, when they are every segment of the scene (four, each
    /// end shared by two of them, exactly), and form a rectangle within
    /// [`RECTANGLE_TOLERANCE`].
    pub(super) fn of(scene: &Scene, walls: &[Wall], extent: f64) -> Option<Shoebox> {
        let segments: usize = scene
            .interfaces()
            .iter()
            .map(|i| i.polyline.num_segments())
            .sum();
        if walls.len() != 4 || segments != 4 || walls.iter().any(|w| w.open != [false; 2]) {
            return None;
        }
        // Walk the corners: c0 → c1 along wall 0, then the wall from c1, and so on.
        let other_end = |w: &Wall, c: Point| -> Option<Point> {
            if w.p == c {
                Some(w.q)
            } else if w.q == c {
                Some(w.p)
            } else {
                None
            }
        };
        let (c0, c1) = (walls[0].p, walls[0].q);
        let mut used = [true, false, false, false];
        let mut corners = [c0, c1, c0, c0];
        let mut by_side = [0usize; 4];
        for side in 1..4 {
            let from = corners[side];
            let (w, to) = (0..4)
                .filter(|&w| !used[w])
                .find_map(|w| other_end(&walls[w], from).map(|to| (w, to)))?;
            used[w] = true;
            by_side[side] = w;
            if side < 3 {
                corners[side + 1] = to;
            } else if to != c0 {
                return None;
            }
        }
        let [c0, c1, c2, c3] = corners;
        if c0 == c1 || c1 == c2 || c2 == c3 || c3 == c0 || c0 == c2 || c1 == c3 {
            return None;
        }
        let (a, b) = (c1 - c0, c3 - c0);
        let (l1, l2) = (a.length(), b.length());
        if !(l1 > 0.0 && l2 > 0.0 && l1.is_finite() && l2.is_finite()) {
            return None;
        }
        let (u, v) = (a * (1.0 / l1), b * (1.0 / l2));
        let angle = u.dot(v).abs();
        let fourth = (c2 - (c0 + a + b)).length() / (l1 + l2);
        if !(angle <= RECTANGLE_TOLERANCE && fourth <= RECTANGLE_TOLERANCE) {
            return None;
        }
        // Each mirroring rounds by a few ulps of the image's coordinates, which grow to
        // about `k (L₁ + L₂) + extent` at depth `k`.
        let round_off = 8.0 * f64::EPSILON * (1.0 + extent / (l1 + l2));
        Some(Shoebox {
            c0,
            u,
            v,
            l1,
            l2,
            // Sides: 0 is c0 → c1 (y = 0), 1 is c1 → c2 (x = L₁), 2 is c2 → c3 (y = L₂),
            // 3 is c3 → c0 (x = 0).
            y0: by_side[0],
            x1: by_side[1],
            y1: by_side[2],
            x0: by_side[3],
            deviation: angle + fourth + round_off,
            shape: angle + fourth,
        })
    }

    /// The walls on the local lines x = 0, x = L₁, y = 0, y = L₂.
    pub(super) fn walls(&self) -> [usize; 4] {
        [self.x0, self.x1, self.y0, self.y1]
    }

    /// `x` in the room's local coordinates.
    fn local(&self, x: Point) -> (f64, f64) {
        let d = x - self.c0;
        (d.dot(self.u), d.dot(self.v))
    }

    /// Whether `x` lies inside the room, farther than the lattice's margin from its walls.
    fn inside(&self, x: Point) -> bool {
        let (lx, ly) = self.local(x);
        let g = 1e-9 * (self.l1 + self.l2);
        lx > g && lx < self.l1 - g && ly > g && ly < self.l2 - g
    }

    /// Whether the lattice serves `search`: its source and every receiver inside the room.
    pub(super) fn serves(&self, search: &MirrorSearch<'_>) -> bool {
        self.inside(search.source) && search.receivers.iter().all(|&r| self.inside(r))
    }

    /// How far (in length) the scene's path of an image of `k` reflections may lie from the
    /// lattice's.
    fn error(&self, k: usize) -> f64 {
        let k = (k + 1) as f64;
        (self.l1 + self.l2) * (1e-9 + 4.0 * k * k * self.deviation)
    }
}

/// One lattice line an image's line crosses: where (the fraction of the way from the image
/// to the receiver) and which wall it stands for.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    t: f64,
    wall: usize,
}

/// The line from an image (lattice cell `cell`, local coordinates `from`) to a receiver
/// (`to`), of `length` and `steps` reflections.
struct Line {
    cell: [i64; 2],
    from: [f64; 2],
    to: [f64; 2],
    length: f64,
    steps: usize,
}

impl Line {
    /// Whether every point where the line meets a wall lies farther than `margin` (across
    /// that wall) from the points before and after it on the path, and from the lattice's
    /// corners: `ends` (the source's and the receiver's least distance to a wall) beyond
    /// `margin`, and every x crossing farther than `margin / min(|dx|, |dy|)` (in fractions
    /// of the line) from every y crossing. The crossings of one axis are `L / |d|` apart;
    /// the two closest of the two axes are found by merging them in order.
    fn clear(&self, room: &Shoebox, ends: f64, margin: f64) -> bool {
        if ends <= margin || ends.is_nan() {
            return false;
        }
        let [i, j] = self.cell;
        if i == 0 || j == 0 {
            return true;
        }
        let [dx, dy] = [self.to[0] - self.from[0], self.to[1] - self.from[1]];
        // The first crossing's fraction of the line, the step to the next, how many.
        let lines = |cell: i64, from: f64, d: f64, len: f64| {
            let m = if cell > 0 { cell } else { cell + 1 };
            (
                (m as f64 * len - from) / d,
                len / d.abs(),
                cell.unsigned_abs(),
            )
        };
        let (a0, step_a, na) = lines(i, self.from[0], dx, room.l1);
        let (b0, step_b, nb) = lines(j, self.from[1], dy, room.l2);
        let limit = margin / dx.abs().min(dy.abs());
        if !limit.is_finite() {
            return false;
        }
        let (mut p, mut q) = (0, 0);
        let (mut a, mut b) = (a0, b0);
        while p < na && q < nb {
            if (a - b).abs() <= limit {
                return false;
            }
            if a < b {
                p += 1;
                a = a0 + p as f64 * step_a;
            } else {
                q += 1;
                b = b0 + q as f64 * step_b;
            }
        }
        true
    }
}

/// The lines of one axis crossed between lattice coordinate `from` (the image's, in cell
/// `cell`) and `to` (the receiver's, in cell 0), in order from the image: line `m L` is
/// wall `low` for even `m` and `high` for odd `m`.
fn crossings(
    cell: i64,
    from: f64,
    to: f64,
    len: f64,
    [low, high]: [usize; 2],
    out: &mut Vec<Crossing>,
) {
    out.clear();
    let wall = |m: i64| if m.rem_euclid(2) == 0 { low } else { high };
    let d = to - from;
    if cell > 0 {
        for m in (1..=cell).rev() {
            out.push(Crossing {
                t: (m as f64 * len - from) / d,
                wall: wall(m),
            });
        }
    } else {
        for m in cell + 1..=0 {
            out.push(Crossing {
                t: (m as f64 * len - from) / d,
                wall: wall(m),
            });
        }
    }
}

/// An image path of a rectangular room in closed form, without its points: what a caller
/// that needs no points (a streaming search) takes instead of the [`MirrorPath`] of the
/// tree's arithmetic ([`MirrorWalls::arrivals_unfolded`]).
///
/// The path is the straight line from the source's lattice image to the receiver, unfolded:
/// its length is the line's, every reflection off the walls on the local lines x = 0 and
/// x = L₁ meets them at one incidence angle (the line's `|dx| / L` its cosine), every one off
/// the walls on y = 0 and y = L₂ at another (`|dy| / L`), and the number of reflections off
/// each wall follows from the image's lattice indices `(i, j)`: `⌈|i|/2⌉` off the wall the
/// first crossing meets and `⌊|i|/2⌋` off the other, alike for `j`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RoomPath {
    /// The receiver's index in the receivers given.
    pub receiver: usize,
    /// Reflections in all (2 or more).
    pub steps: usize,
    /// The path's length `L` and travel time.
    pub length: f64,
    pub time: f64,
    /// The walls (indices into [`MirrorWalls`]) on x = 0, x = L₁, y = 0, y = L₂, with the
    /// reflections off each.
    pub walls: [(usize, u64); 4],
    /// `|cos θ|` of the incidence on the x walls and on the y walls (`|dx| / L`, `|dy| / L`).
    pub cos: [f64; 2],
}

/// The reflections off the walls at lattice line `0` and line `L` of the image in cell
/// `cell` of one axis: the first line its line crosses is `m = cell` (odd: the wall at `L`)
/// for `cell > 0` and `m = cell + 1` (even: the wall at 0) for `cell < 0`, and they
/// alternate.
fn reflections_off(cell: i64) -> [u64; 2] {
    let n = cell.unsigned_abs();
    if cell > 0 {
        [n / 2, n.div_ceil(2)]
    } else {
        [n.div_ceil(2), n / 2]
    }
}

/// The search's state while it lists a room's images.
struct Lister<'a, 'b, 's, F, P> {
    walls: &'a MirrorWalls,
    search: &'a MirrorSearch<'s>,
    found: &'b mut F,
    /// Where the caller takes paths in closed form (it needs no points): each image whose
    /// path is certain goes there instead of through the tree's arithmetic.
    unfolded: Option<&'b mut dyn FnMut(&RoomPath) -> bool>,
    progress: &'b mut P,
    stats: MirrorStats,
    granted: u64,
    /// The work done since the last poll of `progress`.
    unpolled: u64,
}

impl MirrorWalls {
    /// [`MirrorWalls::arrivals`] in the rectangle `room` (whose [`Shoebox::serves`] holds):
    /// the same paths (to the bit) in another order. A beam is an image here: the limits of
    /// beams, work and depth count images, the legs of the paths validated and their
    /// reflections.
    ///
    /// Where `unfolded` is given, each image whose path is certain (below) goes there in
    /// closed form ([`RoomPath`]), without its points, and every other one to `found` as
    /// without it: the shallow paths (fewer than 2 reflections), those whose time lies
    /// within 1e-12 of `max_time` (so that which paths are in time stays the tree's
    /// decision), those of a rectangle that is one only to its tolerance once deep enough
    /// for its deviation to reach 1e-13 of the length, and those whose line passes a lattice
    /// corner, or meets a wall with the source or receiver, or with the next or previous
    /// crossing, nearer (across the wall) than 1e-9 of the path's length and coordinates
    /// plus four times the lattice's error: there the tree's validation may drop the path
    /// (a corner, a vanished leg, a leg on the wall's line). Elsewhere the tree's validation
    /// keeps the path with the lattice's sequence (the crossings in order), so the two give
    /// the same arrivals, to round-off.
    #[expect(
        clippy::too_many_arguments,
        reason = "the tree's arguments and the closed forms' sink"
    )]
    pub(super) fn room_arrivals(
        &self,
        room: &Shoebox,
        search: &MirrorSearch<'_>,
        bounds: &Bounds,
        scratch: &mut MirrorScratch,
        found: &mut impl FnMut(MirrorPath<'_>) -> bool,
        unfolded: Option<&mut dyn FnMut(&RoomPath) -> bool>,
        progress: &mut impl FnMut(u64) -> bool,
    ) -> MirrorStats {
        let mut lister = Lister {
            walls: self,
            search,
            found,
            // (The closure's own lifetime shortened to the lister's.)
            unfolded: unfolded.map(|u| u as &mut dyn FnMut(&RoomPath) -> bool),
            progress,
            stats: MirrorStats::default(),
            granted: 0,
            unpolled: 0,
        };
        if bounds.late(search.source, None) {
            return lister.stats;
        }
        let max_steps = search.max_steps.min(search.max_depth);
        let (sx, sy) = room.local(search.source);
        let image = |i: i64, len: f64, x: f64| {
            i as f64 * len + if i.rem_euclid(2) == 0 { x } else { len - x }
        };
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        let mut sequence = Vec::new();
        // How near the source comes to a wall (across it).
        let clear = |x: f64, y: f64| x.min(room.l1 - x).min(y).min(room.l2 - y);
        for (r, &receiver) in search.receivers.iter().enumerate() {
            let (rx, ry) = room.local(receiver);
            let ends = clear(sx, sy).min(clear(rx, ry));
            let coord = crate::problem::coord(search.source, receiver);
            // Every image within reach (and the lattice's error) of the receiver, and
            // within `max_steps` reflections.
            let pad = room.error(max_steps) + 4.0 * bounds.delta;
            let reach = bounds.reach + pad;
            // One deeper than walked where the depth limit cuts `max_steps`, to tell.
            let deeper = usize::from(search.max_steps > max_steps);
            let n = (max_steps + deeper).min(i64::MAX as usize / 4) as i64;
            let cells = |len: f64, span: f64| -> i64 {
                let c = (span / len).ceil() + 1.0;
                if c.is_finite() && c < n as f64 {
                    c as i64
                } else {
                    n
                }
            };
            let ni = cells(room.l1, reach);
            for i in -ni..=ni {
                let x = image(i, room.l1, sx);
                let dx = x - rx;
                if dx.abs() > reach {
                    continue;
                }
                let left = n - i.abs();
                let span = (reach * reach - dx * dx).max(0.0).sqrt();
                let nj = cells(room.l2, span).min(left);
                for j in -nj..=nj {
                    let y = image(j, room.l2, sy);
                    let dy = y - ry;
                    if dx.hypot(dy) > reach {
                        continue;
                    }
                    let k = (i.abs() + j.abs()) as usize;
                    if k > max_steps {
                        // The depth limit, beyond which paths may remain.
                        lister.stats.stopped = true;
                        continue;
                    }
                    if !lister.beam(k) {
                        return lister.stats;
                    }
                    let length = dx.hypot(dy);
                    if lister.unfolded.is_some() {
                        let line = Line {
                            cell: [i, j],
                            from: [x, y],
                            to: [rx, ry],
                            length,
                            steps: k,
                        };
                        if let Some(go) = lister.closed_form(room, r, &line, ends, coord) {
                            if !go {
                                return lister.stats;
                            }
                            continue;
                        }
                    }
                    crossings(i, x, rx, room.l1, [room.x0, room.x1], &mut xs);
                    crossings(j, y, ry, room.l2, [room.y0, room.y1], &mut ys);
                    // A near tie: an x and a y crossing closer (along the line) than the
                    // lattice's error, over the sine of the line's angle to the axes.
                    let sine = (dx.abs().min(dy.abs()) / length).max(f64::MIN_POSITIVE);
                    let tie = room.error(k) / sine / length.max(f64::MIN_POSITIVE);
                    if !lister.image(r, &xs, &ys, tie, &mut sequence, scratch) {
                        return lister.stats;
                    }
                }
            }
        }
        lister.stats
    }
}

impl<F, P> Lister<'_, '_, '_, F, P>
where
    F: FnMut(MirrorPath<'_>) -> bool,
    P: FnMut(u64) -> bool,
{
    /// One more path validated, of `legs` legs: its work counted, the run polled. `false`
    /// where `max_work` or the run stops the search.
    fn validated(&mut self, legs: u64) -> bool {
        self.stats.leaves += 1;
        self.stats.work += legs;
        if self.stats.work > self.search.max_work {
            self.stats.stopped = true;
            return false;
        }
        self.unpolled += legs;
        if self.unpolled >= POLL_WORK {
            self.unpolled = 0;
            if !(self.progress)(0) {
                self.stats.stopped = true;
                return false;
            }
        }
        true
    }

    /// The path of `line` to receiver `r` in closed form, to the caller's `unfolded`, where
    /// it is certain ([`MirrorWalls::room_arrivals`] says when): `Some(go)` (`false` where
    /// the search stops), or `None` where the path goes through the tree's arithmetic.
    /// `ends` is how near the source or the receiver comes to a wall, `coord` their largest
    /// coordinate. Counts the same work as the tree's validation of the path.
    fn closed_form(
        &mut self,
        room: &Shoebox,
        r: usize,
        line: &Line,
        ends: f64,
        coord: f64,
    ) -> Option<bool> {
        let k = line.steps;
        if k < 2 || 4.0 * (k + 1) as f64 * room.shape > 1e-13 {
            return None;
        }
        let time = self.search.medium().time_along(line.length);
        let max_time = self.search.max_time;
        if max_time.is_finite() && (time - max_time).abs() <= 1e-12 * max_time {
            return None;
        }
        let margin = 1e-9 * (line.length + coord) + 4.0 * room.error(k);
        if !line.clear(room, ends, margin) {
            return None;
        }
        if !self.validated(k as u64 + 1) {
            return Some(false);
        }
        if time > max_time {
            return Some(true);
        }
        let [i, j] = line.cell;
        let ([x0, x1], [y0, y1]) = (reflections_off(i), reflections_off(j));
        let [dx, dy] = [line.to[0] - line.from[0], line.to[1] - line.from[1]];
        let path = RoomPath {
            receiver: r,
            steps: k,
            length: line.length,
            time,
            walls: [(room.x0, x0), (room.x1, x1), (room.y0, y0), (room.y1, y1)],
            cos: [dx.abs() / line.length, dy.abs() / line.length],
        };
        let go = (self.unfolded.as_mut()?)(&path);
        if !go {
            // The caller's stop (its limit of arrivals): the list is short.
            self.stats.stopped = true;
        }
        Some(go)
    }

    /// One more image of `k` reflections: `false` where a limit or the run stops the search.
    fn beam(&mut self, k: usize) -> bool {
        if k == 0 {
            return true;
        }
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
        true
    }

    /// The paths of one image to receiver `r`, its lattice crossings `xs` and `ys`: one
    /// sequence where no crossings are nearer than `tie` (in fractions of the line), every
    /// order of the near-tied ones else. `false` where the search stops.
    fn image(
        &mut self,
        r: usize,
        xs: &[Crossing],
        ys: &[Crossing],
        tie: f64,
        sequence: &mut Vec<usize>,
        scratch: &mut MirrorScratch,
    ) -> bool {
        sequence.clear();
        let (mut a, mut b) = (0, 0);
        let mut near = false;
        while a < xs.len() || b < ys.len() {
            if a < xs.len() && b < ys.len() {
                near |= (xs[a].t - ys[b].t).abs() <= tie;
                if xs[a].t <= ys[b].t {
                    sequence.push(xs[a].wall);
                    a += 1;
                } else {
                    sequence.push(ys[b].wall);
                    b += 1;
                }
            } else if a < xs.len() {
                sequence.push(xs[a].wall);
                a += 1;
            } else {
                sequence.push(ys[b].wall);
                b += 1;
            }
        }
        if !near {
            return self.path(r, sequence, false, scratch);
        }
        // Every order of the near-tied crossings, each with the whole validation.
        self.orders(r, xs, ys, tie, scratch)
    }

    /// Every order of `xs` and `ys` that keeps each axis's order and puts a crossing first
    /// only where it is not later than the other axis's next by more than `tie`, depth first
    /// (an explicit stack of the places where both could come first: paths are thousands of
    /// reflections deep). `false` where the search stops.
    fn orders(
        &mut self,
        r: usize,
        xs: &[Crossing],
        ys: &[Crossing],
        tie: f64,
        scratch: &mut MirrorScratch,
    ) -> bool {
        let mut prefix = Vec::with_capacity(xs.len() + ys.len());
        // Where both could come first and the x crossing was taken: (a, b, prefix length).
        let mut forks: Vec<(usize, usize, usize)> = Vec::new();
        let (mut a, mut b) = (0, 0);
        let mut orders = 0;
        loop {
            while a < xs.len() || b < ys.len() {
                let x_first = a < xs.len() && (b == ys.len() || xs[a].t <= ys[b].t + tie);
                let y_first = b < ys.len() && (a == xs.len() || ys[b].t <= xs[a].t + tie);
                if x_first {
                    if y_first {
                        forks.push((a, b, prefix.len()));
                    }
                    prefix.push(xs[a].wall);
                    a += 1;
                } else {
                    prefix.push(ys[b].wall);
                    b += 1;
                }
            }
            orders += 1;
            if orders > MAX_ORDERS {
                // Too many to try: say the list may be short.
                self.stats.stopped = true;
                return false;
            }
            if !self.path(r, &prefix, true, scratch) {
                return false;
            }
            let Some((fa, fb, len)) = forks.pop() else {
                return true;
            };
            prefix.truncate(len);
            prefix.push(ys[fb].wall);
            (a, b) = (fa, fb + 1);
        }
    }

    /// The path of wall sequence `sequence` to receiver `r` through the tree's arithmetic
    /// (with the crossing test where `crossings`), reported if valid and in time. `false`
    /// where the search stops.
    fn path(
        &mut self,
        r: usize,
        sequence: &[usize],
        crossings: bool,
        scratch: &mut MirrorScratch,
    ) -> bool {
        let search = self.search;
        let walls = &self.walls.walls;
        let MirrorScratch {
            stack,
            walls: sequence_walls,
            points,
            rel,
            lens,
            far,
            ..
        } = scratch;
        stack.clear();
        stack.push(Node {
            wall: usize::MAX,
            image: search.source,
            beam: None,
            next: 0,
        });
        let mut image = search.source;
        for &w in sequence {
            image = walls[w].mirror(image);
            stack.push(Node {
                wall: w,
                image,
                beam: None,
                next: 0,
            });
        }
        sequence_walls.clear();
        sequence_walls.extend_from_slice(sequence);
        if !self.validated(stack.len() as u64) {
            return false;
        }
        let mut validation = Validation {
            search,
            walls,
            points,
            rel,
            lens,
            far,
            crossings,
            crossers: None,
        };
        let receiver = search.receivers[r];
        let Some((length, reason)) = validation.path(stack, receiver) else {
            return true;
        };
        let time = search.medium().time_along(length);
        if time > search.max_time {
            return true;
        }
        let go = (self.found)(MirrorPath {
            receiver: r,
            walls: sequence_walls,
            points,
            time,
            status: if reason.is_some() {
                Status::Obstructed
            } else {
                Status::Converged
            },
            reason,
        });
        if !go {
            // The caller's stop (its limit of arrivals): the list is short.
            self.stats.stopped = true;
        }
        go
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One listed path: receiver, walls, points, time, status.
    type Listed = (usize, Vec<usize>, Vec<Point>, f64, Status);

    /// A room of `corners` (one closed polyline, or one interface per wall), speed 343.
    fn room(corners: &[[f64; 2]], one_polyline: bool) -> Scene {
        let pts = |c: &[[f64; 2]]| {
            c.iter()
                .map(|p| format!("[{:?}, {:?}]", p[0], p[1]))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let interfaces = if one_polyline {
            format!(
                r#""walls": {{ "points": [{}], "closed": true }}"#,
                pts(corners)
            )
        } else {
            (0..corners.len())
                .map(|i| {
                    let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                    format!(r#""w{i}": {{ "points": [{}] }}"#, pts(&[a, b]))
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        // The scene's own source and receiver at the corners' mean (the tests give theirs).
        let n = corners.len() as f64;
        let mx = corners.iter().map(|p| p[0]).sum::<f64>() / n;
        let my = corners.iter().map(|p| p[1]).sum::<f64>() / n;
        let doc = format!(
            r#"{{ "media": {{ "air": {{ "speed": 343.0 }} }}, "background": "air",
                "interfaces": {{ {interfaces} }},
                "sources": [[{mx:?}, {my:?}]], "receivers": [[{mx:?}, {my:?}]],
                "paths": [{{ "steps": [] }}] }}"#
        );
        Scene::from_json(&doc).unwrap()
    }

    /// The search of `walls` from `source` to `receivers`.
    fn search<'a>(
        scene: &'a Scene,
        source: Point,
        receivers: &'a [Point],
        max_steps: usize,
        max_time: f64,
        obstructed: bool,
    ) -> MirrorSearch<'a> {
        MirrorSearch {
            scene,
            source,
            receivers,
            max_steps,
            max_depth: crate::scene::MAX_SEARCH_STEPS,
            max_time,
            slowness: 1.0 / 343.0,
            obstructed,
            max_beams: u64::MAX,
            max_work: u64::MAX,
        }
    }

    /// Every path of `search` through the lattice (`tree` false) or the beam tree, sorted.
    fn listing(
        walls: &MirrorWalls,
        search: &MirrorSearch<'_>,
        tree: bool,
    ) -> (Vec<Listed>, MirrorStats) {
        let mut out = Vec::new();
        let found = &mut |p: MirrorPath<'_>| {
            out.push((
                p.receiver,
                p.walls.to_vec(),
                p.points.to_vec(),
                p.time,
                p.status,
            ));
            true
        };
        let scratch = &mut MirrorScratch::default();
        let stats = if tree {
            walls.tree_arrivals(search, scratch, found, &mut |_| true)
        } else {
            walls.arrivals(search, scratch, found, &mut |_| true)
        };
        out.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
        (out, stats)
    }

    /// The lattice's paths are the tree's: the same sequences to the same receivers, with
    /// the same points and times to the bit.
    fn assert_same(lattice: &[Listed], tree: &[Listed], what: &str) {
        assert_eq!(lattice.len(), tree.len(), "{what}: path counts");
        for (a, b) in lattice.iter().zip(tree) {
            assert_eq!((a.0, &a.1), (b.0, &b.1), "{what}: sequences");
            assert_eq!(a.2, b.2, "{what}: points of {:?}", a.1);
            assert_eq!(a.3.to_bits(), b.3.to_bits(), "{what}: time of {:?}", a.1);
            assert_eq!(a.4, b.4, "{what}: status of {:?}", a.1);
        }
    }

    const LISTENERS: [[f64; 2]; 5] = [[4.5, 2.7], [3.8, 1.0], [2.2, 3.1], [0.4, 0.3], [5.6, 0.8]];

    /// The benchmark's 6 × 4 room (one closed polyline, and one interface per wall), five
    /// listeners, 150 ms (paths of up to some 20 reflections): the lattice lists exactly the
    /// tree's paths.
    #[test]
    fn the_room_gives_the_trees_paths() {
        let corners = [[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]];
        let receivers: Vec<Point> = LISTENERS.iter().map(|p| Point::new(p[0], p[1])).collect();
        for one in [true, false] {
            let scene = room(&corners, one);
            let walls =
                MirrorWalls::new(&scene, &(0..scene.interfaces().len()).collect::<Vec<_>>());
            assert!(walls.shoebox.is_some());
            for obstructed in [false, true] {
                let s = search(
                    &scene,
                    Point::new(1.5, 1.2),
                    &receivers,
                    1000,
                    0.15,
                    obstructed,
                );
                let (lattice, ls) = listing(&walls, &s, false);
                let (tree, ts) = listing(&walls, &s, true);
                assert_same(&lattice, &tree, "6 x 4 room");
                assert!(lattice.len() > 5 * 250, "{}", lattice.len());
                assert!(!ls.stopped && !ts.stopped);
                // One validation a path here, as in the tree.
                assert_eq!(ls.leaves, ts.leaves);
            }
        }
    }

    /// A 5 × 3 rectangle turned by 0.6 rad about an offset corner (its corners rounded):
    /// still a rectangle within the tolerance, and the lattice lists the tree's paths.
    #[test]
    fn a_turned_rectangle_gives_the_trees_paths() {
        let (c, s) = (0.6f64.cos(), 0.6f64.sin());
        let at = |x: f64, y: f64| [10.3 + c * x - s * y, -2.7 + s * x + c * y];
        let corners = [at(0.0, 0.0), at(5.0, 0.0), at(5.0, 3.0), at(0.0, 3.0)];
        let scene = room(&corners, true);
        let walls = MirrorWalls::new(&scene, &[0]);
        assert!(walls.shoebox.is_some());
        let receivers: Vec<Point> = [[1.1, 2.3], [4.2, 0.4], [2.5, 1.5], [0.2, 2.9]]
            .iter()
            .map(|p| {
                let q = at(p[0], p[1]);
                Point::new(q[0], q[1])
            })
            .collect();
        let q = at(3.3, 0.8);
        let source = Point::new(q[0], q[1]);
        let s = search(&scene, source, &receivers, 1000, 0.08, false);
        let (lattice, _) = listing(&walls, &s, false);
        let (tree, _) = listing(&walls, &s, true);
        assert_same(&lattice, &tree, "turned rectangle");
        assert!(lattice.len() > 4 * 150, "{}", lattice.len());
    }

    /// [`MirrorWalls::arrivals_unfolded`] of `search`: the paths it gave through the tree's
    /// arithmetic (sorted), those in closed form (sorted by receiver and time), its stats.
    fn unfolded_listing(
        walls: &MirrorWalls,
        search: &MirrorSearch<'_>,
    ) -> (Vec<Listed>, Vec<RoomPath>, MirrorStats) {
        let mut out = Vec::new();
        let mut closed = Vec::new();
        let stats = walls.arrivals_unfolded(
            search,
            &mut MirrorScratch::default(),
            &mut |p: MirrorPath<'_>| {
                out.push((
                    p.receiver,
                    p.walls.to_vec(),
                    p.points.to_vec(),
                    p.time,
                    p.status,
                ));
                true
            },
            &mut |u: &RoomPath| {
                closed.push(*u);
                true
            },
            &mut |_| true,
        );
        out.sort_by(|a, b| (a.0, &a.1).cmp(&(b.0, &b.1)));
        closed.sort_by(|a, b| {
            (a.receiver, a.time)
                .partial_cmp(&(b.receiver, b.time))
                .unwrap()
        });
        (out, closed, stats)
    }

    /// [`unfolded_listing`] against [`listing`] of `search`: the same stats and paths, the
    /// rest to the bit, the closed forms to 1e-12 (see `closed_forms_are_the_validated_paths`):
    /// how many in closed form, of how many.
    fn assert_closed_forms(
        walls: &MirrorWalls,
        sr: &MirrorSearch<'_>,
        what: &str,
    ) -> (usize, usize) {
        let (all, _) = listing(walls, sr, false);
        let scratch = &mut MirrorScratch::default();
        let plain_stats =
            Some(walls.arrivals(sr, scratch, &mut |_: MirrorPath<'_>| true, &mut |_| true));
        let (rest, closed, stats) = unfolded_listing(walls, sr);
        assert_eq!(Some(stats), plain_stats, "{what}: stats");
        assert_eq!(rest.len() + closed.len(), all.len(), "{what}: count");
        // The rest as before, to the bit; the others in closed form.
        let mut others: Vec<&Listed> = all.iter().filter(|p| !rest.contains(p)).collect();
        assert_eq!(others.len(), closed.len(), "{what}: the rest is listed");
        let counts = |p: &Listed, u: &RoomPath| {
            u.walls
                .map(|(w, _)| p.1.iter().filter(|&&x| x == w).count() as u64)
        };
        // Whether every leg of `p` meets its wall at `u`'s cosine for the wall's pair (a
        // short leg's direction from its points rounds more: the points are found from
        // images as far as the path is long).
        let cosines = |p: &Listed, u: &RoomPath| {
            p.1.iter().enumerate().all(|(i, &w)| {
                let d = p.2[i + 1] - p.2[i];
                let cos = (d.dot(walls.walls[w].n) / d.length()).abs();
                let pair = usize::from(w != u.walls[0].0 && w != u.walls[1].0);
                let tol = 1e-13 + 8.0 * f64::EPSILON * u.length / d.length();
                (cos - u.cos[pair]).abs() <= tol
            })
        };
        for u in &closed {
            // The path of the same receiver, time (1e-12), reflections per wall and cosines
            // (equal times are common in a symmetric room).
            let at = others.iter().position(|p| {
                p.0 == u.receiver
                    && (p.3 - u.time).abs() <= 1e-12 * p.3
                    && counts(p, u) == u.walls.map(|(_, n)| n)
                    && cosines(p, u)
            });
            let Some(at) = at else {
                panic!("{what}: no validated path for {u:?}");
            };
            let p = others.swap_remove(at);
            assert_eq!(p.1.len(), u.steps, "{what}: {:?}", p.1);
            let legs: f64 = p.2.windows(2).map(|w| w[0].distance(w[1])).sum();
            assert!(
                (legs - u.length).abs() <= 1e-12 * legs,
                "{what}: length of {:?}",
                p.1
            );
        }
        (closed.len(), all.len())
    }

    /// The closed forms of [`MirrorWalls::arrivals_unfolded`] against the tree's arithmetic
    /// ([`MirrorWalls::arrivals`], with points) in random rectangles (axis-aligned and
    /// turned, one polyline or four interfaces), random sources and receivers, some near a
    /// wall, paths of up to about 60 reflections: the same paths (the closed forms for most
    /// of them, the rest given as before, bit for bit), the same stats; each closed form's
    /// time and length within 1e-12 of the validated path's, its reflections per wall those
    /// of the path's sequence, its two cosines every leg's with its wall's normal (1e-12).
    ///
    /// Mutants caught: the counts per wall swapped, the cosines swapped, a path near a corner
    /// or a wall taken in closed form where the tree drops it.
    #[test]
    fn closed_forms_are_the_validated_paths() {
        let mut rng = crate::demo::SplitMix64(7);
        let (mut closed_total, mut total, mut near_wall) = (0, 0, 0);
        for round in 0..24 {
            let (l1, l2) = (1.0 + 9.0 * rng.next_f64(), 0.5 + 6.0 * rng.next_f64());
            let turned = round % 3 == 2;
            let angle = if turned { 6.0 * rng.next_f64() } else { 0.0 };
            let (c, s) = (angle.cos(), angle.sin());
            let (ox, oy) = (20.0 * rng.next_f64() - 10.0, 20.0 * rng.next_f64() - 10.0);
            let at = |x: f64, y: f64| {
                if turned {
                    [ox + c * x - s * y, oy + s * x + c * y]
                } else {
                    [x, y]
                }
            };
            let corners = [at(0.0, 0.0), at(l1, 0.0), at(l1, l2), at(0.0, l2)];
            let scene = room(&corners, round % 2 == 0);
            let all_walls: Vec<usize> = (0..scene.interfaces().len()).collect();
            let walls = MirrorWalls::new(&scene, &all_walls);
            assert!(walls.shoebox.is_some(), "round {round}");
            let mut inside = |near: bool| {
                let (x, y) = (rng.next_f64(), rng.next_f64());
                let (mut x, y) = (0.02 * l1 + 0.96 * l1 * x, 0.02 * l2 + 0.96 * l2 * y);
                if near {
                    // A few 1e-9 of the room from a wall: the closed form leaves such paths
                    // to the tree's validation, which may drop them.
                    x = (l1 + l2) * (2e-9 + 5e-9 * rng.next_f64());
                }
                let q = at(x, y);
                Point::new(q[0], q[1])
            };
            let source = inside(false);
            let near = round % 4 == 3;
            let receivers: Vec<Point> = (0..3).map(|k| inside(near && k == 0)).collect();
            let max_time = 12.0 * (l1 + l2) / 343.0;
            let sr = search(&scene, source, &receivers, 1000, max_time, false);
            let (closed, all) = assert_closed_forms(&walls, &sr, &format!("round {round}"));
            assert!(closed > 0);
            closed_total += closed;
            total += all;
            near_wall += usize::from(near);
        }
        // Nearly every path in closed form (the rest: the shallow ones, those near a wall).
        assert!(near_wall > 0);
        assert!(closed_total * 10 > total * 8, "{closed_total} of {total}");
        // Lines through and near the corners of a square (`paths_through_corners_are_the_trees`):
        // the tree drops the paths through a corner, and so do the closed forms.
        let scene = room(&[[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]], true);
        let walls = MirrorWalls::new(&scene, &[0]);
        let receivers = [
            Point::new(3.0, 3.0),
            Point::new(2.0, 2.0),
            Point::new(3.0, 1.0),
            Point::new(1.0, 3.0),
            Point::new(3.0, 3.0 + 1e-14),
            Point::new(3.0, 3.0 + 1e-8),
        ];
        let sr = search(
            &scene,
            Point::new(1.0, 1.0),
            &receivers,
            12,
            f64::INFINITY,
            false,
        );
        assert!(!listing(&walls, &sr, false).1.stopped);
        let (closed, all) = assert_closed_forms(&walls, &sr, "corners");
        assert!(closed > 0 && closed < all, "{closed} of {all}");
    }

    /// Lines through the room's corners: a 4 × 4 square, source (1, 1) and receivers on
    /// its diagonals, whose image lines pass exactly through lattice corners (no path
    /// there, as the tree says), and near them.
    #[test]
    fn paths_through_corners_are_the_trees() {
        let corners = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
        let scene = room(&corners, true);
        let walls = MirrorWalls::new(&scene, &[0]);
        let receivers = [
            Point::new(3.0, 3.0),
            Point::new(2.0, 2.0),
            Point::new(3.0, 1.0),
            Point::new(1.0, 3.0),
            Point::new(3.0, 3.0 + 1e-14),
        ];
        for obstructed in [false, true] {
            let s = search(
                &scene,
                Point::new(1.0, 1.0),
                &receivers,
                12,
                f64::INFINITY,
                obstructed,
            );
            let (lattice, ls) = listing(&walls, &s, false);
            let (tree, _) = listing(&walls, &s, true);
            assert_same(&lattice, &tree, "corners");
            assert!(!ls.stopped);
        }
    }

    /// Not a rectangle: a parallelogram, a quadrilateral whose corner is off by 1e-9, five
    /// walls, and a room with one more interface inside: the tree serves them.
    #[test]
    fn only_rectangles_take_the_lattice() {
        let skew = room(&[[0.0, 0.0], [6.0, 0.0], [7.0, 4.0], [1.0, 4.0]], true);
        assert!(MirrorWalls::new(&skew, &[0]).shoebox.is_none());
        let off = room(
            &[[0.0, 0.0], [6.0, 0.0], [6.0, 4.0 + 1e-9], [0.0, 4.0]],
            true,
        );
        assert!(MirrorWalls::new(&off, &[0]).shoebox.is_none());
        let five = room(
            &[[0.0, 0.0], [3.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]],
            true,
        );
        assert!(MirrorWalls::new(&five, &[0]).shoebox.is_none());
        // Four walls but one not reflecting.
        let four = room(&[[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]], false);
        assert!(MirrorWalls::new(&four, &[0, 1, 2]).shoebox.is_none());
        assert!(MirrorWalls::new(&four, &[0, 1, 2, 3]).shoebox.is_some());
        // A receiver on a wall, or outside: the tree.
        let rect = room(&[[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]], true);
        let walls = MirrorWalls::new(&rect, &[0]);
        let room = walls.shoebox.unwrap();
        let on = [Point::new(6.0, 1.0)];
        assert!(!room.serves(&search(&rect, Point::new(1.0, 1.0), &on, 3, 1.0, false)));
        let out = [Point::new(7.0, 1.0)];
        assert!(!room.serves(&search(&rect, Point::new(1.0, 1.0), &out, 3, 1.0, false)));
    }

    /// A thin room (10 × 0.01) searched 20,000 reflections deep: its images cost thousands of
    /// reflections each, and a stop request answered at the first poll ends the search
    /// within about [`POLL_WORK`] of work, long before its first block of beams is spent.
    ///
    /// Mutant caught: the lattice polling its run only per block of images.
    #[test]
    fn a_deep_search_polls_its_run_by_work() {
        let rect = room(&[[0.0, 0.0], [10.0, 0.0], [10.0, 0.01], [0.0, 0.01]], true);
        let walls = MirrorWalls::new(&rect, &[0]);
        let receivers = [Point::new(7.0, 0.004)];
        let mut polls = 0;
        let stats = walls.arrivals(
            &search(
                &rect,
                Point::new(2.0, 0.007),
                &receivers,
                20_000,
                f64::INFINITY,
                false,
            ),
            &mut MirrorScratch::default(),
            &mut |_: MirrorPath<'_>| true,
            &mut |beams| {
                polls += usize::from(beams == 0);
                beams > 0
            },
        );
        assert!(stats.stopped && polls == 1, "{stats:?}");
        assert!(stats.work < POLL_WORK + 2 * 20_000, "{stats:?}");
        assert!(stats.beams < PROGRESS_BEAMS, "{stats:?}");
    }

    /// `max_steps`, `max_time`, the depth limit, the beams limit and a stop through
    /// `progress`, against the unbounded listing truncated: the paths of at most
    /// `max_steps` reflections; those by `max_time`; a subset, said stopped.
    #[test]
    fn limits_truncate_the_unbounded_listing() {
        let rect = room(&[[0.0, 0.0], [6.0, 0.0], [6.0, 4.0], [0.0, 4.0]], true);
        let walls = MirrorWalls::new(&rect, &[0]);
        let receivers = [Point::new(4.5, 2.7), Point::new(0.7, 1.7)];
        let source = Point::new(1.5, 1.2);
        let all = listing(
            &walls,
            &search(&rect, source, &receivers, 9, f64::INFINITY, false),
            false,
        )
        .0;
        // Every image of at most 9 reflections: 2 (9² + 10²) per... 181 per receiver.
        assert_eq!(all.len(), 2 * (2 * 9 * 10 + 1));
        let steps = listing(
            &walls,
            &search(&rect, source, &receivers, 4, f64::INFINITY, false),
            false,
        );
        let expected: Vec<&Listed> = all.iter().filter(|p| p.1.len() <= 4).collect();
        assert_eq!(steps.0.iter().collect::<Vec<_>>(), expected);
        assert!(!steps.1.stopped);
        let times = listing(
            &walls,
            &search(&rect, source, &receivers, 9, 0.05, false),
            false,
        );
        let expected: Vec<&Listed> = all.iter().filter(|p| p.3 <= 0.05).collect();
        assert_eq!(times.0.iter().collect::<Vec<_>>(), expected);
        assert!(expected.len() < all.len() && !expected.is_empty());
        // The depth limit below max_steps.
        let mut deep = search(&rect, source, &receivers, 9, f64::INFINITY, false);
        deep.max_depth = 4;
        let (d, ds) = listing(&walls, &deep, false);
        assert!(ds.stopped);
        assert_eq!(
            d.iter().collect::<Vec<_>>(),
            all.iter().filter(|p| p.1.len() <= 4).collect::<Vec<_>>()
        );
        // The beams limit.
        let mut few = search(&rect, source, &receivers, 9, f64::INFINITY, false);
        few.max_beams = 50;
        let (f, fs) = listing(&walls, &few, false);
        assert!(fs.stopped && fs.beams == 50, "{fs:?}");
        assert!(!f.is_empty() && f.len() < all.len());
        assert!(f.iter().all(|p| all.contains(p)));
        // The caller stops at its third path: three listed, said stopped.
        let mut three = 0;
        let stats = walls.arrivals(
            &search(&rect, source, &receivers, 9, f64::INFINITY, false),
            &mut MirrorScratch::default(),
            &mut |_: MirrorPath<'_>| {
                three += 1;
                three < 3
            },
            &mut |_| true,
        );
        assert!(stats.stopped && three == 3, "{stats:?}");
        // A stop requested at the first ask: nothing listed.
        let mut none = Vec::new();
        let stats = walls.arrivals(
            &search(&rect, source, &receivers, 9, f64::INFINITY, false),
            &mut MirrorScratch::default(),
            &mut |p: MirrorPath<'_>| {
                none.push(p.time);
                true
            },
            &mut |_| false,
        );
        assert!(stats.stopped);
        // Only the direct paths come before the first beam's ask.
        assert!(none.len() <= 1, "{none:?}");
    }
}
