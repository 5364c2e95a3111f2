//! The unit tests' scenes: a search of one of a scene's paths, built as `search_sequence`
//! builds it, so that a test can call the search's own steps.

use crate::geom::Point;
use crate::scene::Scene;
use crate::trace::Classifier;
use crate::trace::classify::Sequence;

use super::{Hierarchy, MAX_TUPLES, Search, SearchOutcome, SequenceSearch, searching};

/// A scene with what a search of its paths borrows.
pub(super) struct Fixture {
    /// The scene.
    pub(super) scene: Scene,
    /// Its classifier.
    classifier: Classifier,
    /// The segment hierarchy of each interface.
    hierarchies: Vec<Hierarchy>,
}

impl Fixture {
    /// The fixture of the scene `json` (which must be valid).
    pub(super) fn new(json: &str) -> Fixture {
        let scene = Scene::from_json(json).unwrap_or_else(|e| panic!("{e}: {json}"));
        let classifier = Classifier::new(&scene);
        let hierarchies = scene
            .interfaces()
            .iter()
            .map(|i| Hierarchy::new(&i.polyline))
            .collect();
        Fixture {
            scene,
            classifier,
            hierarchies,
        }
    }

    /// Runs `f` on the input of a search of path `path` (its media given) from the scene's
    /// first source to its first receiver, with at most `max_tuples` tuples.
    pub(super) fn with_input<R>(
        &self,
        path: usize,
        max_tuples: usize,
        f: impl FnOnce(SequenceSearch<'_>) -> R,
    ) -> R {
        let sequence = Sequence::of(&self.scene, path);
        let hierarchies: Vec<&Hierarchy> = sequence
            .steps
            .iter()
            .map(|s| &self.hierarchies[s.interface])
            .collect();
        let media = self.scene.paths()[path].media.as_deref();
        f(SequenceSearch {
            run: crate::options::Run::unbounded(),
            scene: &self.scene,
            classifier: &self.classifier,
            hierarchies: &hierarchies,
            tolerance: self.scene.solver().tolerance,
            sequence,
            media: media.expect("a fixture's path gives its media"),
            source: self.scene.sources()[0],
            receiver: self.scene.receivers()[0],
            budget: super::SearchBudget::tuples(max_tuples),
        })
    }

    /// Runs `f` on the search of path `path` (see [`with_input`](Self::with_input)); returns
    /// what `f` returns and what the search did.
    pub(super) fn search<R>(
        &self,
        path: usize,
        f: impl FnOnce(&mut Search<'_>) -> R,
    ) -> (R, SearchOutcome) {
        self.with_input(path, MAX_TUPLES, |input| {
            let mut result = None;
            let stats = searching(input, |search| result = Some(f(search)));
            (result.expect("the search ran"), stats)
        })
    }
}

/// `points` as a JSON array of pairs (each number as Rust prints it: read back exactly).
pub(super) fn points_json(points: &[Point]) -> String {
    let pairs: Vec<String> = points
        .iter()
        .map(|p| format!("[{:?}, {:?}]", p.x, p.y))
        .collect();
    format!("[{}]", pairs.join(", "))
}
