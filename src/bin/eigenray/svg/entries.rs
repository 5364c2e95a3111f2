//! What a picture draws: its entries (the rays, every stationary path of each, a search's
//! arrivals) as items, and past [`MAX_RAYS`] an evenly spread sample of them.

use eigenray::scene::Step;
use eigenray::{Point, RaySet, Scene, SearchArrival, Status};

use super::MAX_RAYS;

/// One entry of the picture: a ray, one stationary path of a ray, or a search arrival.
#[derive(Clone, Debug)]
pub(super) struct Item {
    /// The source's index.
    pub(super) source: usize,
    /// The receiver's index.
    pub(super) receiver: usize,
    /// The path (`None` for a search arrival).
    pub(super) path: Option<usize>,
    /// The step sequence.
    pub(super) steps: Vec<Step>,
    /// Its place among its triple's stationary paths (`"stationary": "all"` only).
    pub(super) arrival: Option<usize>,
    /// How its solve ended.
    pub(super) status: Status,
    /// Travel time; NaN when it has none.
    pub(super) time: f64,
    /// The ray's points, source to receiver.
    pub(super) points: Vec<Point>,
    /// Leg media (indices into [`Scene::media`]), when known.
    pub(super) media: Vec<usize>,
    /// Its direction at the source, where the points alone do not fix the ray (a
    /// `profile` medium's stationary path or search arrival).
    pub(super) launch_angle: Option<f64>,
    /// The points drawn, its curved legs sampled (`None`: drawn through `points`).
    pub(super) curve: Option<Vec<Point>>,
}

/// The entries a picture draws from: its rays (in any form) and a search's arrivals.
pub(super) struct Entries<'a> {
    /// The scene traced.
    scene: &'a Scene,
    /// The rays, in any form.
    pub(super) rays: RaySet<'a>,
    /// Where each triple's entries start (`RaySet::Stationary` only).
    starts: Vec<usize>,
    /// The search's arrivals.
    pub(super) arrivals: &'a [SearchArrival],
}

impl<'a> Entries<'a> {
    /// The entries of `rays` and `arrivals`, traced in `scene`.
    pub(super) fn new(
        scene: &'a Scene,
        rays: RaySet<'a>,
        arrivals: &'a [SearchArrival],
    ) -> Entries<'a> {
        let mut starts = Vec::new();
        if let RaySet::Stationary(st) = rays {
            let mut n = 0;
            for t in &st.triples {
                starts.push(n);
                n += t.arrivals.len().max(1);
            }
        }
        Entries {
            scene,
            rays,
            starts,
            arrivals,
        }
    }

    /// Entries of the rays (one per ray, or per stationary path and per triple without one).
    pub(super) fn rays_len(&self) -> usize {
        match self.rays {
            RaySet::Rays(r) => r.len(),
            RaySet::Batch(b) => b.len(),
            RaySet::Stationary(st) => st.entries(),
        }
    }

    /// Entries in all: the rays' and the arrivals.
    fn len(&self) -> usize {
        self.rays_len() + self.arrivals.len()
    }

    /// The steps of path `p`.
    fn steps(&self, p: usize) -> Vec<Step> {
        self.scene
            .paths()
            .get(p)
            .map(|p| p.steps.clone())
            .unwrap_or_default()
    }

    /// Entry `i`: the rays' entries first, then the arrivals.
    fn item(&self, i: usize) -> Item {
        let n = self.rays_len();
        if i >= n {
            let a = &self.arrivals[i - n];
            return Item {
                source: a.source,
                receiver: a.receiver,
                path: None,
                steps: a.steps.clone(),
                arrival: None,
                status: a.arrival.status,
                time: a.arrival.time,
                points: a.arrival.points.clone(),
                media: a.arrival.media.clone(),
                launch_angle: a.arrival.launch_angle,
                curve: None,
            };
        }
        let ray = |r: eigenray::Ray| Item {
            source: r.source,
            receiver: r.receiver,
            path: Some(r.path),
            steps: self.steps(r.path),
            arrival: None,
            status: r.status,
            time: r.time,
            points: r.points,
            media: r.media,
            launch_angle: None,
            curve: None,
        };
        match self.rays {
            RaySet::Rays(rays) => ray(rays[i].clone()),
            RaySet::Batch(batch) => ray(batch.ray(i)),
            RaySet::Stationary(st) => {
                let k = self.starts.partition_point(|&s| s <= i) - 1;
                let t = &st.triples[k];
                let arrival = i - self.starts[k];
                let mut item = Item {
                    source: t.source,
                    receiver: t.receiver,
                    path: Some(t.path),
                    steps: self.steps(t.path),
                    arrival: Some(arrival),
                    status: if t.complete {
                        Status::NoPath
                    } else {
                        Status::NotConverged
                    },
                    time: f64::NAN,
                    points: Vec::new(),
                    media: Vec::new(),
                    launch_angle: None,
                    curve: None,
                };
                if let Some(a) = t.arrivals.get(arrival) {
                    item.status = a.status;
                    item.time = a.time;
                    item.points = a.points.clone();
                    item.media = a.media.clone();
                    item.launch_angle = a.launch_angle;
                }
                item
            }
        }
    }

    /// The items drawn: every drawable entry, or past [`MAX_RAYS`] those of a sample (their
    /// curves not yet sampled).
    pub(super) fn drawn(&self) -> Drawn {
        let (picked, sampled) = sample(self.len());
        let items: Vec<Item> = picked
            .iter()
            .map(|&i| self.item(i))
            .filter(drawable)
            .collect();
        Drawn { items, sampled }
    }

    /// Entries without a time (never drawn).
    pub(super) fn timeless(&self) -> usize {
        let has = |status: Status, time: f64| status.has_time() && time.is_finite();
        match self.rays {
            RaySet::Rays(r) => r.iter().filter(|r| !has(r.status, r.time)).count(),
            RaySet::Batch(b) => b
                .records()
                .iter()
                .filter(|r| !has(r.status, r.time))
                .count(),
            RaySet::Stationary(st) => {
                let none = st.triples.iter().filter(|t| t.arrivals.is_empty()).count();
                let bad = st
                    .triples
                    .iter()
                    .flat_map(|t| &t.arrivals)
                    .filter(|a| !has(a.status, a.time))
                    .count();
                none + bad
            }
        }
    }
}

/// The items a picture draws, and whether they are a sample of its entries.
pub(super) struct Drawn {
    /// The drawn items, in the entries' order.
    pub(super) items: Vec<Item>,
    /// Whether they were picked from more than [`MAX_RAYS`] entries.
    pub(super) sampled: bool,
}

/// Whether an item is drawn: it has a finite time and at least two finite points.
fn drawable(r: &Item) -> bool {
    r.status.has_time()
        && r.time.is_finite()
        && r.points.len() >= 2
        && r.points.iter().all(|p| p.is_finite())
}

/// The entries to draw out of `n`: every one, or past [`MAX_RAYS`] a stratified sample (one
/// at a pseudo-random place in each of [`MAX_RAYS`] equal runs of the ray order), so that a
/// regular grid of receivers or a set of paths does not alias with a stride. The second value
/// says whether it is a sample.
fn sample(n: usize) -> (Vec<usize>, bool) {
    if n <= MAX_RAYS {
        return ((0..n).collect(), false);
    }
    let mut x = 0x9e37_79b9_7f4a_7c15_u64;
    let picked = (0..MAX_RAYS)
        .map(|k| {
            // xorshift64: a fixed sequence, so the same batch gives the same picture.
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let (lo, hi) = (k * n / MAX_RAYS, (k + 1) * n / MAX_RAYS);
            lo + (x % (hi - lo) as u64) as usize
        })
        .collect();
    (picked, true)
}
