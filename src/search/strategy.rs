//! Which strategy lists which arrivals of which step sequences: the one partition of the
//! sequences between the beam tree (`beams.rs`) and the walk over sequences
//! (`sequences.rs`), decided by [`owner`] from what a sequence is made of ([`Shape`]).
//!
//! | a sequence's | specular arrivals (`converged`, `obstructed`) | `vertex` arrivals (when asked) |
//! | --- | --- | --- |
//! | reflections only, no interface with vertices | the beam tree | none is listed |
//! | reflections only, some off an interface with vertices | the beam tree | the walk |
//! | with a refraction | the walk | the walk |
//! | any, in a scene with curved legs (the direct ray too) | the walk | the walk |
//!
//! The beam tree covers every reflect-only sequence by construction (the image method from
//! each source, every segment of each allowed interface a wall); the walk asks [`owner`] for
//! each sequence it visits what to search and list, and prunes a prefix only where no
//! extension of it is the walk's (its rule "need", checked against [`owner`] by the tests
//! below). A scene with a medium whose speed has a gradient has curved legs: no images, so
//! every sequence there (the direct ray and the reflect-only ones too) goes to the walk. A
//! new strategy (beam tracing of polylines) is a new [`Strategy`] and a new row here.

use crate::scene::{SearchOptions, Step, StepKind};

/// A strategy of the search.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Strategy {
    /// The beam tree: the image method from each source (`beams.rs`, `trace/mirrors.rs`).
    BeamTree,
    /// The walk over sequences, each searched completely per pair (`sequences.rs`).
    Walk,
}

/// The kinds of arrival a sequence may have, as the partition tells them apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum ArrivalKind {
    /// A specular path: `converged`, or `obstructed` when the search lists those.
    Specular,
    /// A path held on a vertex of an interface (`vertex`).
    Vertex,
}

/// What decides which strategy searches a sequence.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Shape {
    /// Whether it has a refraction.
    pub refracts: bool,
    /// Whether it reflects off an interface with vertices.
    pub vertices: bool,
    /// Whether its scene has curved legs (a medium with a gradient): no image method.
    pub curved: bool,
}

impl Shape {
    /// The shape of the sequence `steps`, `has_vertices` telling per interface (scene index)
    /// whether a path can be held on one of its vertices.
    #[cfg(test)]
    pub fn of(steps: &[Step], has_vertices: &[bool], curved: bool) -> Shape {
        let start = Shape {
            curved,
            ..Shape::default()
        };
        steps
            .iter()
            .fold(start, |shape, &step| shape.then(step, has_vertices))
    }

    /// The shape of this sequence followed by `step`.
    #[inline]
    pub fn then(self, step: Step, has_vertices: &[bool]) -> Shape {
        Shape {
            refracts: self.refracts || step.kind == StepKind::Refract,
            vertices: self.vertices
                || (step.kind == StepKind::Reflect && has_vertices[step.interface]),
            curved: self.curved,
        }
    }
}

/// The strategy that lists the arrivals of kind `kind` of the (non-empty) sequences of shape
/// `shape`, or `None` where the search lists none (`vertex` arrivals not asked for, or a
/// reflect-only sequence without vertices). The direct ray (no steps) is the beam tree's root,
/// and the walk's in a scene with curved legs.
pub(crate) fn owner(shape: Shape, kind: ArrivalKind, options: &SearchOptions) -> Option<Strategy> {
    match kind {
        ArrivalKind::Specular if shape.refracts || shape.curved => Some(Strategy::Walk),
        ArrivalKind::Specular => Some(Strategy::BeamTree),
        ArrivalKind::Vertex => {
            (options.vertex && (shape.refracts || shape.vertices)).then_some(Strategy::Walk)
        }
    }
}

/// Whether the walk must go on from a prefix of shape `shape`: whether the prefix or some
/// extension of it is the walk's ([`owner`]), told whether a reflection off an interface with
/// vertices can follow with `vertex` arrivals asked for (`vertex_ahead`) and whether a
/// refraction can follow (`refraction_ahead`, asked last: it looks at media). The walk's rule
/// "need": a prefix for which this is false is pruned with everything below it.
#[inline]
pub(crate) fn walk_may_extend(
    shape: Shape,
    vertex_ahead: bool,
    refraction_ahead: impl FnOnce() -> bool,
) -> bool {
    shape.refracts || shape.curved || vertex_ahead || refraction_ahead()
}

/// What `strategy` lists of a sequence of shape `shape`: which kinds of arrival.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Claim {
    /// Its specular arrivals.
    pub specular: bool,
    /// Its `vertex` arrivals.
    pub vertex: bool,
}

impl Claim {
    /// The arrivals of a sequence of shape `shape` that `strategy` lists.
    pub fn of(strategy: Strategy, shape: Shape, options: &SearchOptions) -> Claim {
        let mine = |kind| owner(shape, kind, options) == Some(strategy);
        Claim {
            specular: mine(ArrivalKind::Specular),
            vertex: mine(ArrivalKind::Vertex),
        }
    }

    /// Whether the strategy lists anything of the sequence.
    pub fn any(self) -> bool {
        self.specular || self.vertex
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Search options over interfaces `0..n` with `vertex` as given.
    fn options(n: usize, vertex: bool) -> SearchOptions {
        SearchOptions {
            max_steps: Some(4),
            max_time: None,
            interfaces: (0..n).collect(),
            reflect: true,
            refract: true,
            obstructed: true,
            vertex,
            diffraction: false,
        }
    }

    /// Every sequence of up to `depth` steps over `n` interfaces, each step a reflection or a
    /// refraction.
    fn sequences(n: usize, depth: usize) -> Vec<Vec<Step>> {
        let steps: Vec<Step> = (0..n)
            .flat_map(|interface| {
                [StepKind::Reflect, StepKind::Refract].map(|kind| Step { kind, interface })
            })
            .collect();
        let mut all = vec![Vec::new()];
        let mut level = vec![Vec::new()];
        for _ in 0..depth {
            level = level
                .iter()
                .flat_map(|s: &Vec<Step>| {
                    steps.iter().map(move |&t| {
                        let mut next = s.clone();
                        next.push(t);
                        next
                    })
                })
                .collect();
            all.extend(level.iter().cloned());
        }
        all
    }

    /// Every sequence of up to 4 steps over three interfaces (one with vertices) is claimed
    /// exactly once for its specular arrivals, and, when asked for, for its `vertex` ones
    /// exactly where some step can hold a path on a vertex (a refraction through any
    /// interface, a reflection off one with vertices); the beam tree claims exactly the
    /// reflect-only sequences' specular arrivals, which is what it walks, and none in a scene
    /// with curved legs (where the direct ray is the walk's too).
    #[test]
    fn every_sequence_is_claimed_exactly_once() {
        let has_vertices = [false, true, false];
        let all = sequences(3, 4);
        assert_eq!(all.len(), 1 + 6 + 36 + 216 + 1296);
        let mut counted = 0;
        for (vertex, curved) in [(false, false), (true, false), (false, true), (true, true)] {
            let options = options(3, vertex);
            let direct = Shape::of(&[], &has_vertices, curved);
            let walk = Claim::of(Strategy::Walk, direct, &options);
            assert_eq!(walk.specular, curved, "the direct ray");
            for steps in all.iter().filter(|s| !s.is_empty()) {
                let shape = Shape::of(steps, &has_vertices, curved);
                let claims = [Strategy::BeamTree, Strategy::Walk]
                    .map(|strategy| Claim::of(strategy, shape, &options));
                let specular = claims.iter().filter(|c| c.specular).count();
                let vertices = claims.iter().filter(|c| c.vertex).count();
                assert_eq!(specular, 1, "{steps:?}");
                let reflect_only = steps.iter().all(|s| s.kind == StepKind::Reflect);
                assert_eq!(claims[0].specular, reflect_only && !curved, "{steps:?}");
                let holds = steps
                    .iter()
                    .any(|s| s.kind == StepKind::Refract || has_vertices[s.interface]);
                assert_eq!(vertices, usize::from(vertex && holds), "{steps:?}");
                assert!(!claims[0].vertex, "the beam tree lists no vertex arrivals");
                counted += 1;
            }
        }
        assert_eq!(counted, 4 * (all.len() - 1));
    }

    /// The walk's rule "need" against the partition, by brute force: for every prefix of up
    /// to 3 steps and every set of allowed steps (reflections, refractions, both; `vertex`
    /// asked or not), [`walk_may_extend`] is true exactly when the prefix or some extension
    /// of it (up to 3 more steps) is the walk's. (Media are left out: with them the rule is
    /// told fewer refractions are possible, and prunes more.) The shape built step by step
    /// is the whole sequence's.
    #[test]
    fn the_walk_prunes_exactly_what_is_not_its_own() {
        let has_vertices = [false, true];
        let mut cases = 0;
        for (reflect, refract, curved) in [
            (true, false, false),
            (false, true, false),
            (true, true, false),
            (true, false, true),
        ] {
            for vertex in [false, true] {
                for interfaces in [vec![0], vec![1], vec![0, 1]] {
                    let options = SearchOptions {
                        interfaces: interfaces.clone(),
                        reflect,
                        refract,
                        ..options(2, vertex)
                    };
                    let choices: Vec<Step> = sequences(2, 1)
                        .into_iter()
                        .flatten()
                        .filter(|s| options.interfaces.contains(&s.interface))
                        .filter(|s| match s.kind {
                            StepKind::Reflect => reflect,
                            StepKind::Refract => refract,
                            StepKind::Diffract { .. } => false,
                        })
                        .collect();
                    let vertex_ahead = vertex
                        && choices
                            .iter()
                            .any(|c| c.kind == StepKind::Reflect && has_vertices[c.interface]);
                    let refraction_ahead = choices.iter().any(|c| c.kind == StepKind::Refract);
                    let over = |depth: usize| {
                        sequences(2, depth)
                            .into_iter()
                            .filter(|s| s.iter().all(|t| choices.contains(t)))
                    };
                    for prefix in over(3).filter(|s| !s.is_empty()) {
                        let start = Shape::of(&[], &has_vertices, curved);
                        let shape = prefix.iter().fold(start, |s, &t| s.then(t, &has_vertices));
                        assert_eq!(shape, Shape::of(&prefix, &has_vertices, curved));
                        let extended = over(3).any(|more| {
                            let whole = more.iter().fold(shape, |s, &t| s.then(t, &has_vertices));
                            Claim::of(Strategy::Walk, whole, &options).any()
                        });
                        let kept = walk_may_extend(shape, vertex_ahead, || refraction_ahead);
                        assert_eq!(kept, extended, "{prefix:?} {options:?}");
                        cases += 1;
                    }
                }
            }
        }
        assert!(cases >= 340, "{cases} prefixes");
    }
}
