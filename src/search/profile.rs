//! The search of a scene with a `profile` medium between flat horizontal walls (a
//! range-independent waveguide: a surface above, a bottom below): per (source, receiver)
//! pair, every ray of the profile from the source to the receiver with at most `max_steps`
//! reflections at the walls (and any number of turning points), arriving by `max_time`,
//! found in the ray-parameter form ([`Profile::arrivals_within`]) as a path's rays are.
//! Each is fixed by its first vertical direction, its number of events (turning points and
//! reflections) and its ray parameter; the launch angle is sampled, so the search is not
//! complete: every arrival says `complete: false`.
//!
//! [`Profile::arrivals_within`]: crate::leg::profile::Profile::arrivals_within

use rayon::prelude::*;

use crate::leg::profile::Bounds;
use crate::options::Progress;
use crate::scene::{SearchOptions, Step};
use crate::trace::{Arrival, Status, Tracer};

use super::{Control, SearchArrival, SearchReport, StreamedArrival};

impl Tracer {
    /// The profile medium a search from `source` runs in: the one found there, or the
    /// scene's only profile medium without regions.
    fn search_profile_medium(&self, source: crate::geom::Point) -> Option<usize> {
        let media = self.scene().media();
        let m = self.source_medium(false, source).or_else(|| {
            let mut profiled = (0..media.len()).filter(|&m| media[m].profile.is_some());
            let first = profiled.next()?;
            (media.len() == 1 || profiled.next().is_none()).then_some(first)
        })?;
        media[m].profile.is_some().then_some(m)
    }

    /// The search of a profile scene (see the module): its report, its arrivals (none when
    /// `control` streams them) and each pair's completeness (always `false`: sampled).
    pub(super) fn search_profile(
        &self,
        options: &SearchOptions,
        control: &Control<'_>,
    ) -> (SearchReport, Vec<SearchArrival>) {
        let scene = self.scene();
        let (ns, nr) = (scene.sources().len(), scene.receivers().len());
        let bounds = Bounds {
            reflections: if options.reflect {
                u32::try_from(options.step_limit()).unwrap_or(u32::MAX)
            } else {
                0
            },
            time: options.time_limit(),
        };
        let sloped = crate::trace::has_sloped_walls(scene);
        let found: Vec<(Vec<SearchArrival>, u64)> = (0..ns * nr)
            .into_par_iter()
            .map(|pair| {
                let (source, receiver) = (pair / nr, pair % nr);
                let mut out = Vec::new();
                if !control.run.keep_going(Progress::items(1)) {
                    return (out, 0);
                }
                let (s, r) = (scene.sources()[source], scene.receivers()[receiver]);
                let Some(m) = self.search_profile_medium(s) else {
                    return (out, 0);
                };
                let (found, work) = if sloped {
                    self.search_sloped_pair(m, [s, r], options, control.run)
                } else {
                    self.walled_pair(m, [s, r], bounds, options)
                };
                for (steps, mut arrival) in found {
                    if let Some(sink) = control.sink {
                        control.listed.stream();
                        sink.arrival(StreamedArrival {
                            source,
                            receiver,
                            steps: steps.len(),
                            diffractions: 0,
                            vertical_reflections: 0,
                            status: arrival.status,
                            time: arrival.time,
                            amplitude: arrival.amplitude.take(),
                        });
                        continue;
                    }
                    if !control.listed.take(steps.len()) {
                        break;
                    }
                    out.push(SearchArrival {
                        source,
                        receiver,
                        steps,
                        arrival,
                        complete: false,
                        heights: Vec::new(),
                    });
                }
                (out, work)
            })
            .collect();
        let mut report = SearchReport {
            incomplete_pairs: ns * nr,
            ..SearchReport::default()
        };
        let mut arrivals = Vec::new();
        for (a, work) in found {
            report.work += work;
            arrivals.extend(a);
        }
        (report, arrivals)
    }

    /// The arrivals of one pair between flat walls within `bounds`, each with its steps, by
    /// time: `converged` ones (and `obstructed` ones when the search lists them) whose
    /// steps are all off allowed interfaces; and the rays found (the work).
    fn walled_pair(
        &self,
        m: usize,
        [s, r]: [crate::geom::Point; 2],
        bounds: Bounds,
        options: &SearchOptions,
    ) -> (Vec<(Vec<Step>, Arrival)>, u64) {
        let Some(profile) = self.scene().media()[m].profile_model() else {
            return (Vec::new(), 0);
        };
        let (rays, _) = self.walled_rays(&profile, s, r, bounds);
        let work = rays.len() as u64;
        let listed = rays
            .into_iter()
            .filter(|w| {
                (w.status == Status::Converged
                    || (options.obstructed && w.status == Status::Obstructed))
                    && w.ray.sums.t <= bounds.time
                    && w.steps
                        .iter()
                        .all(|st| options.interfaces.contains(&st.interface))
            })
            .map(|w| {
                let arrival = self.walled_arrival(m, &w);
                (w.steps, arrival)
            })
            .collect();
        (listed, work)
    }
}
