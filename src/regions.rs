//! Regions of the plane cut out by the interfaces and the domain box, and their media.

use std::collections::VecDeque;
use std::fmt;

use spade::handles::{
    DirectedEdgeHandle, FixedDirectedEdgeHandle, FixedFaceHandle, FixedVertexHandle,
    PossiblyOuterTag, VertexHandle,
};
use spade::{
    CdtEdge, ConstrainedDelaunayTriangulation, HasPosition, HintGenerator, MAX_ALLOWED_VALUE,
    MIN_ALLOWED_VALUE, Point2, PositionInTriangulation, Triangulation,
};

use crate::geom::{Aabb, Point, Segment, orient, vertex_side};
use crate::scene::{Interface, Scene, SceneError};

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>, (), (), (), QuietHint>;
type EdgeRef<'a> = DirectedEdgeHandle<'a, Point2<f64>, (), CdtEdge<()>, ()>;
type VertexRef<'a> = VertexHandle<'a, Point2<f64>, (), CdtEdge<()>, ()>;

/// "No region" marker in the compact tables.
const NONE: u32 = u32::MAX;

/// Most pairs of interface segments with overlapping boxes that region lookup triangulates
/// (a sea floor of 100,000 segments has about 300,000; 1,400 parallel diagonals reach it).
const MAX_BOX_OVERLAPS: usize = 2_000_000;

/// The media on the two sides of an interface at one point (medium indices into
/// [`Scene::media`]; `None` where the region there has no medium).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sides {
    /// Medium on the side the segment's normal points to (its tangent turned counter-clockwise).
    pub left: Option<usize>,
    /// Medium on the other side.
    pub right: Option<usize>,
}

/// Where the previous point lookup of one caller ended, to start the next one nearby.
///
/// Each thread (or each ray) keeps its own, so lookups share no mutable state. The default hint
/// knows nothing and starts from a coarse grid over the triangulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LocateHint {
    /// Index of a triangulation vertex near the last query (`u32::MAX`: none).
    vertex: u32,
}

impl Default for LocateHint {
    fn default() -> Self {
        LocateHint { vertex: NONE }
    }
}

/// One piece of an interface segment between two consecutive triangulation vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Piece {
    /// Arclength (the polyline's own parameter) where the piece starts.
    start: f64,
    /// Region on the left of the segment.
    left: u32,
    /// Region on the right.
    right: u32,
}

/// The regions of a scene and their media: point lookup and the media on both sides of every
/// interface segment.
///
/// A constrained Delaunay triangulation (`spade`) holds every interface segment as a constraint
/// edge, plus the domain box's edges when the scene has a domain. Its faces are flood-filled into
/// regions that constraint edges separate; every medium's `at` point claims the region holding it
/// and the other regions take the background medium. Region 0 is always the unbounded one: the
/// outside of every closed curve and, with a domain, everything outside the domain box. Without
/// a domain, only closed curves enclose regions.
///
/// Which media lie on the two sides of an interface is precomputed from the triangulation's own
/// edges, so [`sides`](Regions::sides) needs no geometric tolerance: every segment keeps its
/// pieces (a segment is split where another interface's vertex lies on it, a T-junction, and
/// where it crosses the domain's edge) with the region on each side.
///
/// Build it once with [`Regions::build`]; it is read-only afterwards and `Send + Sync`, so rayon
/// threads can share it (each with its own [`LocateHint`]).
///
/// A point exactly on a boundary between two different regions (an interface, or the domain's
/// edge) belongs to no region: [`region_at`](Regions::region_at) and
/// [`medium_at`](Regions::medium_at) return `None` there. On a curve that separates nothing (a
/// dangling open polyline) the point belongs to the one region around it.
#[derive(Clone)]
pub struct Regions {
    cdt: Cdt,
    scale: Scale,
    /// Region of every triangulation face, by face index (the outer face is region 0).
    face_region: Vec<u32>,
    /// Medium of every region.
    region_medium: Vec<Option<usize>>,
    grid: HintGrid,
    /// Interface vertices, all interfaces one after the other.
    verts: Vec<Point>,
    /// Index in `verts` of each interface's first vertex (one more entry at the end).
    vert_offset: Vec<usize>,
    /// Scene-wide index of each interface's first segment (one more entry at the end).
    seg_offset: Vec<usize>,
    /// Index in `pieces` of each scene-wide segment's first piece (one more entry at the end).
    piece_offset: Vec<usize>,
    pieces: Vec<Piece>,
}

impl fmt::Debug for Regions {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Regions")
            .field("regions", &self.region_medium.len())
            .field("region_medium", &self.region_medium)
            .field("vertices", &self.cdt.num_vertices())
            .field("faces", &self.cdt.num_all_faces())
            .field("pieces", &self.pieces.len())
            .finish()
    }
}

impl Regions {
    /// Triangulates the scene's interfaces (and its domain box) and assigns the media.
    ///
    /// `O(M log M)` for `M` interface segments. The scene must come from
    /// [`Scene::from_spec`] (interfaces that neither cross nor overlap); coordinates are held
    /// exactly when they span at most `2^REGION_RANGE_BITS` (what the scene checks when it
    /// needs region lookup), smaller ones are flushed to zero.
    ///
    /// # Errors
    /// `media.NAME.at` when two `at` points lie in one region; `interfaces` when more than
    /// 2,000,000 pairs of segment boxes overlap (the triangulation's work would grow beyond
    /// what a machine can do), or the triangulation fails (which a valid scene does not cause);
    /// and the media checks of the scene format (no medium anywhere, a background or a medium
    /// filling no region, a source without a medium, a refraction at an interface dividing
    /// nothing in a scene without a domain).
    pub fn build(scene: &Scene) -> Result<Regions, SceneError> {
        // Long segments whose boxes overlap by the thousand (parallel diagonals) make the
        // constrained triangulation's work grow faster than quadratically (2,500 such
        // segments: 13 s, 5,000: 3 min): refused before it starts rather than left to hang.
        if scene.box_overlaps_exceed(MAX_BOX_OVERLAPS) {
            return Err(SceneError::new(
                "interfaces",
                format!(
                    "too many interface segments lie across each other's extent for region \
                     lookup (more than {MAX_BOX_OVERLAPS} pairs of overlapping bounding \
                     boxes): give every path its `media`, or use fewer, shorter segments"
                ),
            ));
        }
        let mut regions = Regions::build_inner(scene)?;
        regions.assign_media(scene)?;
        regions.check_media(scene)?;
        Ok(regions)
    }

    /// Refuses media assignments that cannot mean what the scene says: no medium anywhere, a
    /// background or a declared medium that fills no region, a source in a region without a
    /// medium, or, in a scene without a domain, a refraction (with media from region lookup)
    /// at an open interface that has the same region on both sides.
    fn check_media(&self, scene: &Scene) -> Result<(), SceneError> {
        let no_domain_hint = if scene.domain().is_none() {
            "; without a `domain`, an open interface divides nothing and only closed ones \
             enclose regions: add a `domain` box whose edges the interfaces end on"
        } else {
            ""
        };
        if self.region_medium.iter().all(Option::is_none) {
            // Blame what asked for region lookup: a path without `media`, else the search.
            let lookup = scene.paths().iter().position(|p| p.media.is_none());
            let regions = "name a `background` medium, or give a medium an `at` point inside \
                           its region";
            let (key, message) = match lookup {
                Some(k) => (
                    format!("paths[{k}].media"),
                    format!(
                        "missing: path {k} takes its leg media from the regions (it has no \
                         `media`), but no medium fills any region: give the path `media` (one \
                         medium name per leg), or {regions}"
                    ),
                ),
                None if scene.search().is_some() => (
                    "search".to_string(),
                    format!(
                        "the search takes its leg media from the regions, but no medium fills \
                         any region: {regions}"
                    ),
                ),
                None => (
                    "background".to_string(),
                    format!("no medium fills any region: {regions}"),
                ),
            };
            return Err(SceneError::new(key, message));
        }
        if let Some(b) = scene.background()
            && !self.region_medium.contains(&Some(b))
        {
            return Err(SceneError::new(
                "background",
                format!(
                    "`{}` fills no region: the `at` points claim every region{no_domain_hint}",
                    scene.media()[b].name
                ),
            ));
        }
        let mut named = vec![false; scene.media().len()];
        for p in scene.paths() {
            for &m in p.media.iter().flatten() {
                named[m] = true;
            }
        }
        for (m, medium) in scene.media().iter().enumerate() {
            if !named[m] && !self.region_medium.contains(&Some(m)) {
                return Err(SceneError::new(
                    format!("media.{}", medium.name),
                    "fills no region and no path names it: give it an `at` point inside its \
                     region, make it the `background`, or name it in a path's `media`",
                ));
            }
        }
        for (k, &p) in scene.sources().iter().enumerate() {
            self.check_source(scene, k, p)?;
        }
        let divides: Vec<bool> = (0..scene.interfaces().len())
            .map(|i| {
                let (first, end) = (self.seg_offset[i], self.seg_offset[i + 1]);
                self.pieces[self.piece_offset[first]..self.piece_offset[end]]
                    .iter()
                    .any(|p| p.left != p.right)
            })
            .collect();
        for (k, path) in scene.paths().iter().enumerate() {
            // With a domain, an open interface that ends inside it divides nothing on purpose
            // (a dangling reflector); without one, every open interface divides nothing.
            if path.media.is_some() || scene.domain().is_some() {
                continue;
            }
            for (j, step) in path.steps.iter().enumerate() {
                let open = !scene.interfaces()[step.interface].polyline.is_closed();
                if step.kind == crate::scene::StepKind::Refract && open && !divides[step.interface]
                {
                    return Err(SceneError::new(
                        format!("paths[{k}].steps[{j}].refract"),
                        format!(
                            "interface `{}` has the same region on both sides, so the \
                             refraction cannot change medium{no_domain_hint}",
                            scene.interfaces()[step.interface].name
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Refuses source `k` at `p` when no medium fills its region (part of the checks of
    /// [`build`](Self::build); alone when a source moves).
    pub(crate) fn check_source(&self, scene: &Scene, k: usize, p: Point) -> Result<(), SceneError> {
        if self.source_medium(scene, p).is_none() {
            return Err(SceneError::new(
                format!("sources[{k}]"),
                "lies in a region that no medium fills (no `at` point claims it and there is \
                 no `background`)",
            ));
        }
        Ok(())
    }

    /// The regions of `scene` without their media: the triangulation of its interfaces (and
    /// domain box), its faces flood-filled into regions, and every segment's pieces with the
    /// regions on their sides.
    fn build_inner(scene: &Scene) -> Result<Regions, SceneError> {
        let interfaces = scene.interfaces();
        let flat = FlatInterfaces::of(interfaces);
        let bounds = TriangulationBox::of(scene, &flat.verts);
        let scale = bounds.scale;
        let UniqueVertices {
            vid,
            unique,
            original,
        } = UniqueVertices::of(&flat.verts, &bounds.corner_points, scale)?;
        let Triangulated {
            mut cdt,
            handle,
            original_by_handle,
        } = Triangulated::of(&unique, original, &vid[flat.verts.len()..])?;
        drop(unique);
        let num_input_vertices = original_by_handle.len();
        let vertex = |k: usize| FixedVertexHandle::from_index(handle[vid[k] as usize] as usize);
        let corner = |c: usize| vertex(flat.verts.len() + c);

        // The domain's edges first, so that each interface segment's insertion below returns its
        // complete chain of edges (split where it crosses the domain's edge).
        if bounds.domain.is_some() {
            for c in 0..4 {
                cdt.add_constraint_and_split(corner(c), corner((c + 1) % 4), |p| p);
            }
        }
        let through = vertices_through_segments(scene, &flat, &handle, &original_by_handle);
        let chains =
            SegmentChains::constrain(&mut cdt, interfaces, &flat, &through, &handle, vertex);
        drop(through);

        let face_region = flood_regions(&cdt, bounds.domain, num_input_vertices);
        let num_regions = face_region
            .iter()
            .filter(|&&r| r != NONE)
            .max()
            .map_or(1, |&r| r as usize + 1);
        let position = |v: u32| -> Point {
            let v = v as usize;
            if v < num_input_vertices {
                original_by_handle[v]
            } else {
                scale.to_scene(cdt.vertex(FixedVertexHandle::from_index(v)).position())
            }
        };
        let pieces = SegmentPieces::of(&cdt, interfaces, &flat, &chains, &face_region, position);

        let grid = HintGrid::build(&cdt);
        Ok(Regions {
            cdt,
            scale,
            face_region,
            region_medium: vec![None; num_regions],
            grid,
            verts: flat.verts,
            vert_offset: flat.vert_offset,
            seg_offset: flat.seg_offset,
            piece_offset: pieces.offset,
            pieces: pieces.pieces,
        })
    }

    /// Every `at` claims its region; every other region gets the background.
    fn assign_media(&mut self, scene: &Scene) -> Result<(), SceneError> {
        let mut claimed: Vec<Option<usize>> = vec![None; self.region_medium.len()];
        for (m, medium) in scene.media().iter().enumerate() {
            let Some(at) = medium.at else { continue };
            let key = format!("media.{}.at", medium.name);
            let region = self.region_at(at).ok_or_else(|| {
                SceneError::new(
                    &key,
                    "lies on the edge of the domain; it must be strictly inside a region",
                )
            })?;
            if let Some(other) = claimed[region] {
                let hint = if scene.domain().is_none() {
                    " (without a `domain`, an open interface divides nothing: add a `domain` \
                     box whose edges the interfaces end on)"
                } else {
                    ""
                };
                return Err(SceneError::new(
                    key,
                    format!(
                        "lies in the same region as media.{}.at{hint}",
                        scene.media()[other].name
                    ),
                ));
            }
            claimed[region] = Some(m);
        }
        for (medium, claim) in self.region_medium.iter_mut().zip(claimed) {
            *medium = claim.or(scene.background());
        }
        Ok(())
    }

    /// Number of regions (region 0 is the unbounded one).
    pub fn num_regions(&self) -> usize {
        self.region_medium.len()
    }

    /// Medium of region `region` (`None`: no medium there, or no such region).
    pub fn region_medium(&self, region: usize) -> Option<usize> {
        self.region_medium.get(region).copied().flatten()
    }

    /// The region holding `p`; `None` when `p` lies exactly on a boundary between two different
    /// regions (an interface or the domain's edge), or is NaN. `O(1)` expected for points spread
    /// like the interfaces' vertices (a walk from a coarse grid of starting vertices).
    pub fn region_at(&self, p: Point) -> Option<usize> {
        self.region_at_with_hint(p, &mut LocateHint::default())
    }

    /// [`region_at`](Self::region_at), starting the search where `hint` points and leaving it
    /// near `p` for the next query.
    pub fn region_at_with_hint(&self, p: Point, hint: &mut LocateHint) -> Option<usize> {
        if p.x.is_nan() || p.y.is_nan() {
            return None;
        }
        let Some(q) = self.scale.query(p) else {
            // Far beyond every vertex: outside everything.
            return Some(0);
        };
        let start = if (hint.vertex as usize) < self.cdt.num_vertices() {
            FixedVertexHandle::from_index(hint.vertex as usize)
        } else {
            self.grid.hint(q)
        };
        let (region, near) = match self.cdt.locate_with_hint(q, start) {
            PositionInTriangulation::OnFace(f) => {
                let face = self.cdt.face(f);
                (self.face_region[f.index()], face.vertices()[0].fix())
            }
            PositionInTriangulation::OnEdge(e) => {
                let e = self.cdt.directed_edge(e);
                let (l, r) = (
                    self.region_of(e.face().fix()),
                    self.region_of(e.rev().face().fix()),
                );
                (if l == r { l } else { NONE }, e.from().fix())
            }
            PositionInTriangulation::OnVertex(v) => {
                let mut region = None;
                for e in self.cdt.vertex(v).out_edges() {
                    let r = self.region_of(e.face().fix());
                    match region {
                        None => region = Some(r),
                        Some(q) if q != r => region = Some(NONE),
                        Some(_) => {}
                    }
                }
                (region.unwrap_or(0), v)
            }
            PositionInTriangulation::OutsideOfConvexHull(e) => {
                (0, self.cdt.directed_edge(e).from().fix())
            }
            PositionInTriangulation::NoTriangulation => (0, start),
        };
        hint.vertex = near.index() as u32;
        (region != NONE).then_some(region as usize)
    }

    /// Medium index of the region holding `p`; `None` when that region has no medium or `p`
    /// lies exactly on a boundary between two regions (see [`region_at`](Self::region_at)).
    pub fn medium_at(&self, p: Point) -> Option<usize> {
        self.region_at(p).and_then(|r| self.region_medium(r))
    }

    /// The medium of a source of `scene` at `p`: that of the region holding it, or, for a
    /// source on the axis of an `axisymmetric` scene where the axis is the `domain`'s left
    /// edge, that of the region on the edge's right (the format's rule).
    pub(crate) fn source_medium(&self, scene: &Scene, p: Point) -> Option<usize> {
        if !scene.source_on_axis_edge(p) {
            return self.medium_at(p);
        }
        let q = self.scale.query(p)?;
        let region = match self.cdt.locate(q) {
            PositionInTriangulation::OnEdge(e) => {
                let e = self.cdt.directed_edge(e);
                // The face on a directed edge's left; an upward edge has its left toward −x.
                let up = e.to().position().y > e.from().position().y;
                let face = if up { e.rev().face() } else { e.face() };
                self.region_of(face.fix())
            }
            PositionInTriangulation::OnFace(f) => self.face_region[f.index()],
            _ => NONE,
        };
        if region == NONE {
            return None;
        }
        self.medium_of_region(region)
    }

    /// [`medium_at`](Self::medium_at) with a per-caller search hint (see [`LocateHint`]).
    pub fn medium_at_with_hint(&self, p: Point, hint: &mut LocateHint) -> Option<usize> {
        self.region_at_with_hint(p, hint)
            .and_then(|r| self.region_medium(r))
    }

    /// The media on both sides of segment `segment` of interface `interface` at arclength `s`
    /// (the polyline's own parameter). Exact and `O(log k)` for a segment split into `k`
    /// pieces (usually 1). `left` is the side that `polyline.normal(segment)` points to.
    ///
    /// An invalid interface or segment index gives `Sides { left: None, right: None }`.
    pub fn sides(&self, interface: usize, segment: usize, s: f64) -> Sides {
        let Some(g) = self.segment_index(interface, segment) else {
            return Sides::default();
        };
        let pieces = &self.pieces[self.piece_offset[g]..self.piece_offset[g + 1]];
        let k = match pieces.get(1..) {
            Some(rest) => rest.partition_point(|p| p.start <= s),
            None => 0,
        };
        match pieces.get(k) {
            Some(p) => Sides {
                left: self.medium_of_region(p.left),
                right: self.medium_of_region(p.right),
            },
            None => Sides::default(),
        }
    }

    /// Every distinct pair of media on the two sides of interface `interface`, over all its
    /// segments (and their pieces), in a fixed order: what a ray may meet at that interface.
    /// Empty for an invalid index.
    pub fn interface_sides(&self, interface: usize) -> Vec<Sides> {
        let (Some(&first), Some(&end)) = (
            self.seg_offset.get(interface),
            self.seg_offset.get(interface + 1),
        ) else {
            return Vec::new();
        };
        let mut out: Vec<Sides> = Vec::new();
        for p in &self.pieces[self.piece_offset[first]..self.piece_offset[end]] {
            let sides = Sides {
                left: self.medium_of_region(p.left),
                right: self.medium_of_region(p.right),
            };
            if !out.contains(&sides) {
                out.push(sides);
            }
        }
        out
    }

    /// The medium on the side of the segment opposite to `from` at arclength `s`: what a ray
    /// coming from `from` refracts into. The side of `from` is decided exactly against the
    /// segment's line; at a vertex between two segments (`s` at the segment's start or end),
    /// the side of the polyline there (the side test's rule: on the inside of the turn, the
    /// side of both segments' lines; elsewhere the other side), with the media of the segment
    /// after the vertex. `None` when `from` lies on that line (or the index is
    /// invalid).
    pub fn medium_across(
        &self,
        interface: usize,
        segment: usize,
        s: f64,
        from: Point,
    ) -> Option<usize> {
        let g = self.segment_index(interface, segment)?;
        let first = self.vert_offset[interface];
        let n = self.vert_offset[interface + 1] - first;
        let nseg = self.seg_offset[interface + 1] - self.seg_offset[interface];
        let closed = nseg == n;
        let local = g - self.seg_offset[interface];
        let vert = |j: usize| self.verts[first + j % n];
        let (a, b) = (vert(local), vert(local + 1));
        let start = self.pieces[self.piece_offset[g]].start;
        // The vertex `s` sits on, as (segment before it, segment after it), if any.
        let vertex = if s <= start && (local > 0 || closed) {
            Some(((local + nseg - 1) % nseg, local))
        } else if (local + 1 < nseg && s >= self.pieces[self.piece_offset[g + 1]].start)
            || (local + 1 == nseg && closed && s >= start + a.distance(b))
        {
            Some((local, (local + 1) % nseg))
        } else {
            None
        };
        let (side, sides) = match vertex {
            None => (orient(a, b, from), self.sides(interface, segment, s)),
            Some((before, after)) => {
                let v = vert(after);
                let (p, q) = (vert(before), vert(after + 1));
                let left = (v - p).cross(q - v) > 0.0;
                let side = vertex_side(left, orient(p, v, from), orient(v, q, from));
                let after_start = self.pieces[self.piece_offset[g - local + after]].start;
                (side, self.sides(interface, after, after_start))
            }
        };
        if side > 0.0 {
            sides.right
        } else if side < 0.0 {
            sides.left
        } else {
            None
        }
    }

    /// Scene-wide index of a segment, if it exists.
    fn segment_index(&self, interface: usize, segment: usize) -> Option<usize> {
        let (&first, &end) = (
            self.seg_offset.get(interface)?,
            self.seg_offset.get(interface + 1)?,
        );
        (segment < end - first).then_some(first + segment)
    }

    fn region_of(&self, face: FixedFaceHandle<PossiblyOuterTag>) -> u32 {
        self.face_region.get(face.index()).copied().unwrap_or(NONE)
    }

    fn medium_of_region(&self, region: u32) -> Option<usize> {
        self.region_medium(region as usize)
    }
}

/// Every interface vertex, all interfaces one after the other, with each interface's offsets.
struct FlatInterfaces {
    /// The vertices.
    verts: Vec<Point>,
    /// Index in `verts` of each interface's first vertex (one more entry at the end).
    vert_offset: Vec<usize>,
    /// Scene-wide index of each interface's first segment (one more entry at the end).
    seg_offset: Vec<usize>,
    /// Segments in all.
    nseg: usize,
}

impl FlatInterfaces {
    /// The vertices of `interfaces`, flattened, with per-interface offsets.
    fn of(interfaces: &[Interface]) -> FlatInterfaces {
        let mut verts = Vec::new();
        let mut vert_offset = Vec::with_capacity(interfaces.len() + 1);
        let mut seg_offset = Vec::with_capacity(interfaces.len() + 1);
        let mut nseg = 0;
        for iface in interfaces {
            vert_offset.push(verts.len());
            seg_offset.push(nseg);
            verts.extend_from_slice(iface.polyline.vertices());
            nseg += iface.polyline.num_segments();
        }
        vert_offset.push(verts.len());
        seg_offset.push(nseg);
        FlatInterfaces {
            verts,
            vert_offset,
            seg_offset,
            nseg,
        }
    }
}

/// The box the triangulation spans, in spade's coordinates, and the scale to them.
struct TriangulationBox {
    /// The exact power-of-two scale between the scene's coordinates and spade's.
    scale: Scale,
    /// The domain box (spade's coordinates), if the scene has one.
    domain: Option<Aabb>,
    /// The box's corners, counter-clockwise from the lower left: the domain's, or a margin box
    /// around the interfaces.
    corner_points: [Point; 4],
}

impl TriangulationBox {
    /// The box of `scene`, whose interface vertices are `verts`.
    fn of(scene: &Scene, verts: &[Point]) -> TriangulationBox {
        // An exact power-of-two scale brings every coordinate into the range spade accepts.
        let geometry = Aabb::around(verts);
        let extent = match scene.domain() {
            Some(d) => geometry.union(d),
            None => geometry,
        };
        let scale = Scale::for_box(extent);

        // Box corners, counter-clockwise from the lower left: the domain's, or a margin box around
        // the interfaces (in spade's coordinates) that keeps every interface off the convex hull.
        let domain = scene.domain().map(|d| scale.aabb(d));
        let corners = match domain {
            Some(d) => d,
            None => {
                let b = if geometry.min.x <= geometry.max.x {
                    scale.aabb(geometry)
                } else {
                    Aabb::from_points(Point::new(-1.0, -1.0), Point::new(1.0, 1.0))
                };
                let margin = 0.1 * b.diagonal() + 1.0;
                Aabb {
                    min: Point::new(b.min.x - margin, b.min.y - margin),
                    max: Point::new(b.max.x + margin, b.max.y + margin),
                }
            }
        };
        let corner_points = [
            Point::new(corners.min.x, corners.min.y),
            Point::new(corners.max.x, corners.min.y),
            Point::new(corners.max.x, corners.max.y),
            Point::new(corners.min.x, corners.max.y),
        ];
        TriangulationBox {
            scale,
            domain,
            corner_points,
        }
    }
}

/// The triangulation's input vertices without duplicates (interfaces share vertices).
struct UniqueVertices {
    /// The index in `unique` of every interface vertex, then of the 4 corners.
    vid: Vec<u32>,
    /// The distinct vertices in spade's coordinates, sorted by x then y.
    unique: Vec<Point2<f64>>,
    /// Original coordinates of each unique vertex (corners: spade's coordinates, unscaled).
    original: Vec<Point>,
}

impl UniqueVertices {
    /// Deduplicates the interface vertices `verts` and the box's `corner_points` (in spade's
    /// coordinates) after scaling the former by `scale`.
    ///
    /// # Errors
    /// `interfaces` when there are too many vertices to number in `u32`.
    fn of(
        verts: &[Point],
        corner_points: &[Point; 4],
        scale: Scale,
    ) -> Result<UniqueVertices, SceneError> {
        let mut scaled: Vec<Point2<f64>> = verts.iter().map(|&p| scale.to_spade(p)).collect();
        scaled.extend(corner_points.iter().map(|p| Point2::new(p.x, p.y)));
        if scaled.len() >= NONE as usize {
            return Err(SceneError::new("interfaces", "too many interface vertices"));
        }
        let mut order: Vec<u32> = (0..scaled.len() as u32).collect();
        order.sort_unstable_by(|&a, &b| {
            let (p, q) = (scaled[a as usize], scaled[b as usize]);
            p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y))
        });
        let mut vid = vec![0u32; scaled.len()];
        let mut unique: Vec<Point2<f64>> = Vec::with_capacity(scaled.len());
        let mut original: Vec<Point> = Vec::with_capacity(scaled.len());
        for &k in &order {
            let p = scaled[k as usize];
            if unique.last() != Some(&p) {
                unique.push(p);
                original.push(
                    verts
                        .get(k as usize)
                        .copied()
                        .unwrap_or_else(|| scale.to_scene(p)),
                );
            }
            vid[k as usize] = (unique.len() - 1) as u32;
        }
        Ok(UniqueVertices {
            vid,
            unique,
            original,
        })
    }
}

/// The triangulation of the unique vertices, before any constraint.
struct Triangulated {
    /// The triangulation.
    cdt: Cdt,
    /// The vertex handle (index) of each unique vertex.
    handle: Vec<u32>,
    /// Original coordinates by vertex handle.
    original_by_handle: Vec<Point>,
}

impl Triangulated {
    /// Triangulates `unique` (with their `original` coordinates): the corners (`corner_ids`,
    /// indices into `unique`) first, so that the triangulation is never degenerate, then the
    /// rest in a biased randomised insertion order. Spade's bulk loading and insertion in
    /// polyline order both take quadratic time on long polylines.
    ///
    /// # Errors
    /// `interfaces` when spade refuses a vertex or merges two distinct ones.
    fn of(
        unique: &[Point2<f64>],
        original: Vec<Point>,
        corner_ids: &[u32],
    ) -> Result<Triangulated, SceneError> {
        let mut cdt = Cdt::new();
        let mut handle = vec![NONE; unique.len()];
        let insertion = corner_ids.iter().copied().chain(
            brio_order(unique)
                .into_iter()
                .filter(|u| !corner_ids.contains(u)),
        );
        for u in insertion {
            let h = cdt.insert(unique[u as usize]).map_err(|e| {
                SceneError::new(
                    "interfaces",
                    format!("cannot triangulate the interfaces: {e:?}"),
                )
            })?;
            handle[u as usize] = h.index() as u32;
        }
        let num_input_vertices = cdt.num_vertices();
        if num_input_vertices != unique.len() || handle.contains(&NONE) {
            return Err(SceneError::new(
                "interfaces",
                "the triangulation merged distinct vertices (internal error)",
            ));
        }
        let mut original_by_handle = vec![Point::default(); num_input_vertices];
        for (u, &h) in handle.iter().enumerate() {
            original_by_handle[h as usize] = original[u];
        }
        Ok(Triangulated {
            cdt,
            handle,
            original_by_handle,
        })
    }
}

/// The vertices lying exactly on each scene-wide segment strictly between its ends (a fault
/// ending on a layer, a domain corner on an interface), in order along it, each with its
/// position along the segment (unnormalised) and its index among the unique vertices: that
/// segment's constraint goes in pieces through them. (Spade's constraint splitting can fail on
/// a constraint through such a vertex that also crosses others.) The scale is a power of two,
/// so exactness in scene coordinates is exactness in spade's.
fn vertices_through_segments(
    scene: &Scene,
    flat: &FlatInterfaces,
    handle: &[u32],
    original_by_handle: &[Point],
) -> Vec<Vec<(f64, u32)>> {
    let interfaces = scene.interfaces();
    let mut through: Vec<Vec<(f64, u32)>> = vec![Vec::new(); flat.nseg];
    for (u, &h) in handle.iter().enumerate() {
        let p = original_by_handle[h as usize];
        scene.segments_through(p, |s| {
            let Segment { start: a, end: b } = interfaces[s.interface as usize]
                .polyline
                .segment(s.segment as usize);
            let along = (p - a).dot(b - a);
            through[flat.seg_offset[s.interface as usize] + s.segment as usize]
                .push((along, u as u32));
        });
    }
    for t in &mut through {
        t.sort_by(|x, y| x.0.total_cmp(&y.0));
    }
    through
}

/// The chain of triangulation vertices along every interface segment, once each is a
/// constraint.
struct SegmentChains {
    /// The vertex handles (indices), every segment's chain one after the other.
    chain: Vec<u32>,
    /// Index in `chain` of each scene-wide segment's first vertex (one more entry at the end).
    offset: Vec<usize>,
}

impl SegmentChains {
    /// Adds every segment of `interfaces` to `cdt` as a constraint (in pieces through the
    /// vertices `through` it; `handle` numbers the unique vertices, `vertex` gives the handle
    /// of interface vertex `k` of `flat`), and collects the chain of vertices along each: the
    /// edges that its insertion returns when they connect its ends, else its two ends.
    fn constrain(
        cdt: &mut Cdt,
        interfaces: &[Interface],
        flat: &FlatInterfaces,
        through: &[Vec<(f64, u32)>],
        handle: &[u32],
        vertex: impl Fn(usize) -> FixedVertexHandle,
    ) -> SegmentChains {
        let mut chain: Vec<u32> = Vec::with_capacity(flat.nseg + flat.verts.len());
        let mut chain_offset: Vec<usize> = Vec::with_capacity(flat.nseg + 1);
        for (i, iface) in interfaces.iter().enumerate() {
            let n = iface.polyline.vertices().len();
            for j in 0..iface.polyline.num_segments() {
                chain_offset.push(chain.len());
                let (u, w) = (
                    vertex(flat.vert_offset[i] + j),
                    vertex(flat.vert_offset[i] + (j + 1) % n),
                );
                let stops = &through[flat.seg_offset[i] + j];
                let mut edges = Vec::new();
                let mut from = u;
                for to in stops
                    .iter()
                    .map(|&(_, v)| FixedVertexHandle::from_index(handle[v as usize] as usize))
                    .chain([w])
                {
                    if to != from {
                        edges.extend(cdt.add_constraint_and_split(from, to, |p| p));
                        from = to;
                    }
                }
                chain.push(u.index() as u32);
                if u == w {
                    continue;
                }
                Self::push_links(cdt, &mut chain, &edges, u, w);
            }
        }
        chain_offset.push(chain.len());
        SegmentChains {
            chain,
            offset: chain_offset,
        }
    }

    /// Appends to `chain` the vertices after `u` along the segment `u → w`: the ends of its
    /// constraint `edges` when they connect `u` to `w`, else `w` alone.
    fn push_links(
        cdt: &Cdt,
        chain: &mut Vec<u32>,
        edges: &[FixedDirectedEdgeHandle],
        u: FixedVertexHandle,
        w: FixedVertexHandle,
    ) {
        let mut at = u;
        let mut connected = true;
        for e in edges {
            let e = cdt.directed_edge(*e);
            connected &= e.from().fix() == at;
            at = e.to().fix();
        }
        if connected && at == w {
            chain.extend(
                edges
                    .iter()
                    .map(|e| cdt.directed_edge(*e).to().fix().index() as u32),
            );
        } else {
            chain.push(w.index() as u32);
        }
    }
}

/// The pieces of every interface segment with the regions on their two sides.
struct SegmentPieces {
    /// The pieces, every segment's one after the other.
    pieces: Vec<Piece>,
    /// Index in `pieces` of each scene-wide segment's first piece (one more entry at the end).
    offset: Vec<usize>,
}

impl SegmentPieces {
    /// The pieces of every segment of `interfaces` along its `chains` in `cdt`, with the
    /// regions (`face_region`) on their two sides; consecutive pieces with the same regions
    /// merge. `position` gives a triangulation vertex's scene coordinates.
    fn of(
        cdt: &Cdt,
        interfaces: &[Interface],
        flat: &FlatInterfaces,
        chains: &SegmentChains,
        face_region: &[u32],
        position: impl Fn(u32) -> Point,
    ) -> SegmentPieces {
        let mut pieces = Vec::with_capacity(flat.nseg);
        let mut piece_offset = Vec::with_capacity(flat.nseg + 1);
        for (i, iface) in interfaces.iter().enumerate() {
            let line = &iface.polyline;
            for j in 0..line.num_segments() {
                let g = flat.seg_offset[i] + j;
                let first = pieces.len();
                piece_offset.push(first);
                let links = &chains.chain[chains.offset[g]..chains.offset[g + 1]];
                let a = line.segment(j).start;
                let (s0, s1) = (line.start(j), line.start(j + 1));
                let tangent = line.tangent(j);
                for pair in links.windows(2) {
                    let (x, y) = (pair[0], pair[1]);
                    let (left, right) = piece_regions(cdt, face_region, x, y);
                    let start = if pieces.len() == first {
                        s0
                    } else {
                        let prev: &Piece = &pieces[pieces.len() - 1];
                        // `max` then `min`, not `clamp`: no panic whatever round-off does.
                        (s0 + (position(x) - a).dot(tangent))
                            .max(prev.start)
                            .min(s1)
                    };
                    match pieces.last() {
                        Some(p) if pieces.len() > first && p.left == left && p.right == right => {}
                        _ => pieces.push(Piece { start, left, right }),
                    }
                }
                if pieces.len() == first {
                    pieces.push(Piece {
                        start: s0,
                        left: NONE,
                        right: NONE,
                    });
                }
            }
        }
        piece_offset.push(pieces.len());
        SegmentPieces {
            pieces,
            offset: piece_offset,
        }
    }
}

/// Regions of the two faces along the triangulation edge `x → y` (left, right), or `NONE`
/// when that edge is missing.
fn piece_regions(cdt: &Cdt, face_region: &[u32], x: u32, y: u32) -> (u32, u32) {
    let (x, y) = (
        FixedVertexHandle::from_index(x as usize),
        FixedVertexHandle::from_index(y as usize),
    );
    let regions = |e: EdgeRef<'_>| {
        (
            face_region[e.face().fix().index()],
            face_region[e.rev().face().fix().index()],
        )
    };
    if let Some(e) = cdt.get_edge_from_neighbors(x, y) {
        return regions(e);
    }
    // Split after it was inserted (only where interfaces come within rounding of each other):
    // take the bend through the vertex nearest to the line x–y.
    let (px, py) = (cdt.vertex(x).position(), cdt.vertex(y).position());
    let line = |p: Point2<f64>| Point::new(p.x, p.y);
    let mut best: Option<(f64, FixedDirectedEdgeHandle)> = None;
    for e in cdt.vertex(x).out_edges().filter(|e| e.is_constraint_edge()) {
        let z = e.to();
        if z.fix() == y
            || cdt
                .get_edge_from_neighbors(z.fix(), y)
                .is_none_or(|f| !f.is_constraint_edge())
        {
            continue;
        }
        let off = orient(line(px), line(py), line(z.position())).abs();
        if best.is_none_or(|(b, _)| off < b) {
            best = Some((off, e.fix()));
        }
    }
    best.map_or((NONE, NONE), |(_, e)| regions(cdt.directed_edge(e)))
}

/// Flood-fills the faces into regions separated by constraint edges. Region 0 holds the outer
/// face and, with a domain, every face outside the domain box.
///
/// A face is outside the box when one of its input vertices (vertex handles below
/// `num_input_vertices`, whose coordinates are exact) lies strictly outside it. The vertices
/// that spade creates where an interface crosses the box's edge are rounded, so they do not
/// count; every pocket outside the box still has an input vertex strictly outside (a segment
/// meets a convex box in one interval), and the rest of the outside is reached across
/// non-constraint edges.
fn flood_regions(cdt: &Cdt, domain: Option<Aabb>, num_input_vertices: usize) -> Vec<u32> {
    let n = cdt.num_all_faces();
    let outer = cdt.outer_face().fix();
    let mut handles = vec![outer; n];
    for f in cdt.fixed_all_faces() {
        if let Some(slot) = handles.get_mut(f.index()) {
            *slot = f;
        }
    }
    let mut region = vec![NONE; n];
    let mut stack = Vec::new();
    region[outer.index()] = 0;
    stack.push(outer);
    if let Some(d) = domain {
        let outside = |v: VertexRef<'_>| {
            let p = v.position();
            v.fix().index() < num_input_vertices
                && (p.x < d.min.x || p.x > d.max.x || p.y < d.min.y || p.y > d.max.y)
        };
        for f in cdt.inner_faces() {
            let k = f.fix().index();
            if f.vertices().into_iter().any(outside) && region[k] == NONE {
                region[k] = 0;
                stack.push(handles[k]);
            }
        }
    }
    let mut current = 0;
    let mut next_seed = 0;
    loop {
        while let Some(f) = stack.pop() {
            let Some(start) = cdt.face(f).adjacent_edge() else {
                continue;
            };
            let mut e = start;
            loop {
                if !e.is_constraint_edge() {
                    let g = e.rev().face().fix();
                    if region[g.index()] == NONE {
                        region[g.index()] = current;
                        stack.push(g);
                    }
                }
                e = e.next();
                if e == start {
                    break;
                }
            }
        }
        while next_seed < n && region[next_seed] != NONE {
            next_seed += 1;
        }
        if next_seed == n {
            break;
        }
        current += 1;
        region[next_seed] = current;
        stack.push(handles[next_seed]);
    }
    region
}

/// A biased randomised insertion order (BRIO: rounds of doubling size, each sorted along a
/// Hilbert curve) of `points`, as indices. With the last inserted vertex as the location hint it
/// inserts in expected `O(n log n)`, also for points along curves and lines. Deterministic.
fn brio_order(points: &[Point2<f64>]) -> Vec<u32> {
    let mut lo = Point2::new(f64::INFINITY, f64::INFINITY);
    let mut hi = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in points {
        lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    let cells = f64::from(u16::MAX);
    let span = |a: f64, b: f64| if b > a { cells / (b - a) } else { 0.0 };
    let (sx, sy) = (span(lo.x, hi.x), span(lo.y, hi.y));
    // `as u32` saturates, so rounding cannot leave the grid.
    let key =
        |p: &Point2<f64>| hilbert_index(((p.x - lo.x) * sx) as u32, ((p.y - lo.y) * sy) as u32);
    let mut order: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| (key(p), i as u32))
        .collect();
    // Fisher-Yates with a fixed xorshift seed.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for i in (1..order.len()).rev() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        order.swap(i, (state % (i as u64 + 1)) as usize);
    }
    // Rounds from the end: the last half, the quarter before it, ...
    let mut end = order.len();
    while end > 0 {
        let start = if end <= 64 { 0 } else { end / 2 };
        order[start..end].sort_unstable();
        end = start;
    }
    order.into_iter().map(|(_, i)| i).collect()
}

/// Position of cell `(x, y)` (each `< 2^16`) along a Hilbert curve through the 2^16 × 2^16 grid.
fn hilbert_index(x: u32, y: u32) -> u64 {
    const N: u32 = 1 << 16;
    let (mut x, mut y) = (x.min(N - 1), y.min(N - 1));
    let mut d = 0u64;
    let mut s = N / 2;
    while s > 0 {
        let rx = u32::from(x & s != 0);
        let ry = u32::from(y & s != 0);
        d += u64::from(s) * u64::from(s) * u64::from((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = N - 1 - x;
                y = N - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    d
}

/// An exact power-of-two scale between scene coordinates and spade's (which must lie within
/// `[MIN_ALLOWED_VALUE, MAX_ALLOWED_VALUE]` in magnitude, or be zero).
#[derive(Clone, Copy, Debug)]
struct Scale {
    /// Exponents `e0 + e1 = e`: scene = spade × 2^e, applied in two steps to stay in range.
    e: [i32; 2],
}

/// The exponent of the largest coordinate in spade's coordinates.
const TOP_EXPONENT: i32 = 198;

/// `2^n` for `n` in `[-1022, 1023]`.
fn pow2(n: i32) -> f64 {
    f64::from_bits(((n.clamp(-1022, 1023) + 1023) as u64) << 52)
}

impl Scale {
    /// The scale that maps the largest coordinate magnitude of `b` to `[2^198, 2^199)`: near
    /// the top of spade's range (`2^201`, with room for the margin box), so that coordinates
    /// down to `2^-340` of the largest stay above its smallest (`2^-142`) and none is
    /// flushed (the scene refuses a wider range, see `REGION_RANGE_BITS`).
    fn for_box(b: Aabb) -> Scale {
        let m = [b.min.x, b.min.y, b.max.x, b.max.y]
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if !(m.is_finite() && m > 0.0) {
            return Scale { e: [0, 0] };
        }
        // The unbiased exponent, also for subnormal numbers.
        let e = if m >= f64::MIN_POSITIVE {
            ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023
        } else {
            -1023 - (m.to_bits().leading_zeros() as i32 - 12)
        };
        let e = e - TOP_EXPONENT;
        Scale {
            e: [e / 2, e - e / 2],
        }
    }

    fn down(self, v: f64) -> f64 {
        let w = v * pow2(-self.e[0]) * pow2(-self.e[1]);
        // Flush what spade cannot represent (at most 2^-142 of the largest coordinate) and -0.
        if w.abs() < MIN_ALLOWED_VALUE { 0.0 } else { w }
    }

    fn to_spade(self, p: Point) -> Point2<f64> {
        Point2::new(self.down(p.x), self.down(p.y))
    }

    fn to_scene(self, p: Point2<f64>) -> Point {
        let up = |v: f64| v * pow2(self.e[0]) * pow2(self.e[1]);
        Point::new(up(p.x), up(p.y))
    }

    fn aabb(self, b: Aabb) -> Aabb {
        Aabb::from_points(
            Point::new(self.down(b.min.x), self.down(b.min.y)),
            Point::new(self.down(b.max.x), self.down(b.max.y)),
        )
    }

    /// A query point in spade's coordinates; `None` when it is not finite or lies far outside
    /// every vertex (beyond spade's range, while every vertex is within a few units).
    fn query(self, p: Point) -> Option<Point2<f64>> {
        let q = self.to_spade(p);
        (q.x.abs() <= MAX_ALLOWED_VALUE && q.y.abs() <= MAX_ALLOWED_VALUE).then_some(q)
    }
}

/// Spade's hint generator for the build: the last inserted vertex. It records no lookups, so
/// queries from several threads write nothing.
#[derive(Clone, Copy, Debug, Default)]
struct QuietHint {
    last: usize,
}

impl HintGenerator<f64> for QuietHint {
    fn get_hint(&self, _: Point2<f64>) -> FixedVertexHandle {
        FixedVertexHandle::from_index(self.last)
    }

    fn notify_vertex_lookup(&self, _: FixedVertexHandle) {}

    fn notify_vertex_inserted(&mut self, vertex: FixedVertexHandle, _: Point2<f64>) {
        self.last = vertex.index();
    }

    fn notify_vertex_removed(
        &mut self,
        _: Option<Point2<f64>>,
        vertex: FixedVertexHandle,
        _: Point2<f64>,
    ) {
        self.last = vertex.index().saturating_sub(1);
    }

    fn initialize_from_triangulation<TR, V>(triangulation: &TR) -> Self
    where
        TR: Triangulation,
        V: HasPosition<Scalar = f64>,
    {
        QuietHint {
            last: triangulation.num_vertices().saturating_sub(1),
        }
    }
}

/// A coarse grid of starting vertices for lookups without a hint: each cell names a vertex in
/// or near it, so a walk starts close to its target.
#[derive(Clone, Debug)]
struct HintGrid {
    min: Point2<f64>,
    inv_cell: [f64; 2],
    n: [usize; 2],
    cells: Vec<u32>,
}

impl HintGrid {
    fn build(cdt: &Cdt) -> HintGrid {
        let mut min = Point2::new(f64::INFINITY, f64::INFINITY);
        let mut max = Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY);
        for v in cdt.vertices() {
            let p = v.position();
            min = Point2::new(min.x.min(p.x), min.y.min(p.y));
            max = Point2::new(max.x.max(p.x), max.y.max(p.y));
        }
        let side = ((cdt.num_vertices() as f64 / 4.0).sqrt().ceil() as usize).clamp(1, 1024);
        let span = |lo: f64, hi: f64| {
            if hi > lo {
                side as f64 / (hi - lo)
            } else {
                0.0
            }
        };
        let mut grid = HintGrid {
            min,
            inv_cell: [span(min.x, max.x), span(min.y, max.y)],
            n: [side, side],
            cells: vec![NONE; side * side],
        };
        for v in cdt.vertices() {
            let c = grid.cell(v.position());
            if grid.cells[c] == NONE {
                grid.cells[c] = v.fix().index() as u32;
            }
        }
        // Empty cells take the vertex of the nearest filled cell (breadth-first).
        let mut queue: VecDeque<usize> = (0..grid.cells.len())
            .filter(|&c| grid.cells[c] != NONE)
            .collect();
        if queue.is_empty() {
            grid.cells.fill(0);
        }
        while let Some(c) = queue.pop_front() {
            let (cx, cy) = (c % side, c / side);
            let near = [
                (cx > 0).then(|| c - 1),
                (cx + 1 < side).then(|| c + 1),
                (cy > 0).then(|| c - side),
                (cy + 1 < side).then(|| c + side),
            ];
            for d in near.into_iter().flatten() {
                if grid.cells[d] == NONE {
                    grid.cells[d] = grid.cells[c];
                    queue.push_back(d);
                }
            }
        }
        grid
    }

    fn cell(&self, p: Point2<f64>) -> usize {
        // `as usize` saturates (negative and NaN give 0).
        let cx = (((p.x - self.min.x) * self.inv_cell[0]) as usize).min(self.n[0] - 1);
        let cy = (((p.y - self.min.y) * self.inv_cell[1]) as usize).min(self.n[1] - 1);
        cy * self.n[0] + cx
    }

    fn hint(&self, p: Point2<f64>) -> FixedVertexHandle {
        FixedVertexHandle::from_index(self.cells[self.cell(p)] as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64) -> Point {
        Point::new(x, y)
    }

    fn regions(json: &str) -> (Scene, Regions) {
        let scene = Scene::from_json(json).unwrap();
        let regions = Regions::build(&scene).unwrap();
        (scene, regions)
    }

    fn medium(scene: &Scene, name: &str) -> Option<usize> {
        Some(scene.medium_index(name).unwrap())
    }

    #[test]
    fn layered_domain() {
        let (scene, r) = regions(
            r#"{
            "media": {
                "a": { "speed": 1, "at": [5, 9] },
                "b": { "speed": 2, "at": [5, 5] },
                "c": { "speed": 3, "at": [5, 1] },
                "d": { "speed": 4, "at": [5, -5] }
            },
            "domain": [[0, -10], [10, 10]],
            "interfaces": {
                "top":    { "points": [[0, 8], [4, 7], [10, 8]] },
                "middle": { "points": [[0, 3], [6, 4], [10, 3]] },
                "bottom": { "points": [[0, 0], [10, 0]] }
            },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        // 4 layers inside the domain plus the outside.
        assert_eq!(r.num_regions(), 5);
        assert_eq!(r.medium_at(p(1.0, 9.5)), medium(&scene, "a"));
        assert_eq!(r.medium_at(p(9.0, 7.0)), medium(&scene, "b"));
        assert_eq!(r.medium_at(p(2.0, 2.0)), medium(&scene, "c"));
        assert_eq!(r.medium_at(p(0.5, -9.9)), medium(&scene, "d"));
        // Outside the domain: no medium (no background).
        assert_eq!(r.region_at(p(-1.0, 5.0)), Some(0));
        assert_eq!(r.medium_at(p(-1.0, 5.0)), None);
        assert_eq!(r.medium_at(p(5.0, 50.0)), None);
        // On an interface and on the domain's edge: no region.
        assert_eq!(r.region_at(p(5.0, 0.0)), None);
        assert_eq!(r.region_at(p(0.0, 5.0)), None);
        // Sides: the normal of a left-to-right segment points up.
        let bottom = scene.interface_index("bottom").unwrap();
        let s = r.sides(bottom, 0, 3.0);
        assert_eq!(
            s,
            Sides {
                left: medium(&scene, "c"),
                right: medium(&scene, "d")
            }
        );
        let top = scene.interface_index("top").unwrap();
        let line = &scene.interfaces()[top].polyline;
        let s = r.sides(top, 1, line.start(1) + 1.0);
        assert_eq!(
            s,
            Sides {
                left: medium(&scene, "a"),
                right: medium(&scene, "b")
            }
        );
        // A hint carried from query to query gives the same answers.
        let mut hint = LocateHint::default();
        for k in 0..200 {
            let y = -9.95 + 0.1 * k as f64;
            let q = p(3.3, y);
            assert_eq!(
                r.medium_at_with_hint(q, &mut hint),
                r.medium_at(q),
                "y = {y}"
            );
        }
        // Invalid indices.
        assert_eq!(r.sides(99, 0, 0.0), Sides::default());
        assert_eq!(r.sides(bottom, 1, 0.0), Sides::default());
        assert_eq!(r.medium_across(bottom, 5, 0.0, p(0.0, 1.0)), None);
    }

    #[test]
    fn interfaces_beyond_the_domain() {
        // Polylines that stick out of the domain are cut by its edges.
        let (scene, r) = regions(
            r#"{
            "media": {
                "up": { "speed": 1, "at": [0, 1] },
                "down": { "speed": 2, "at": [0, -1] },
                "out": { "speed": 3 }
            },
            "background": "out",
            "domain": [[-2, -2], [2, 2]],
            "interfaces": { "s": { "points": [[-3, 0.1], [3, -0.1]] } },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        assert_eq!(r.num_regions(), 3);
        assert_eq!(r.medium_at(p(1.9, 1.9)), medium(&scene, "up"));
        assert_eq!(r.medium_at(p(-1.9, -1.9)), medium(&scene, "down"));
        assert_eq!(r.medium_at(p(2.5, 1.0)), medium(&scene, "out"));
        assert_eq!(r.medium_at(p(2.5, -1.0)), medium(&scene, "out"));
        let sides = |s| r.sides(0, 0, s);
        let len = scene.interfaces()[0].polyline.length();
        assert_eq!(
            sides(0.5),
            Sides {
                left: medium(&scene, "out"),
                right: medium(&scene, "out")
            }
        );
        assert_eq!(
            sides(len / 2.0),
            Sides {
                left: medium(&scene, "up"),
                right: medium(&scene, "down")
            }
        );
        assert_eq!(
            sides(len - 0.5),
            Sides {
                left: medium(&scene, "out"),
                right: medium(&scene, "out")
            }
        );
        assert_eq!(
            r.medium_across(0, 0, len / 2.0, p(0.0, 1.0)),
            medium(&scene, "down")
        );
    }

    #[test]
    fn zigzag_across_the_domain_edge() {
        // A polyline in and out of the domain across its top edge: every dip inside closes a
        // pocket under the edge; the parts outside merge with the outside.
        let mut pts = Vec::new();
        for k in 0..41 {
            let y = if k % 2 == 0 {
                10.0 + 0.37 + 0.013 * k as f64
            } else {
                10.0 - 0.29 - 0.007 * k as f64
            };
            pts.push(format!("[{}, {}]", 0.3 + 0.2371 * k as f64, y));
        }
        let json = format!(
            r#"{{
            "media": {{ "main": {{ "speed": 1, "at": [5, 5] }}, "pocket": {{ "speed": 2 }} }},
            "background": "pocket",
            "domain": [[0, 0], [10, 10]],
            "interfaces": {{ "zig": {{ "points": [{}] }} }},
            "sources": [], "receivers": [], "paths": []
        }}"#,
            pts.join(",")
        );
        let (scene, r) = regions(&json);
        let (main, pocket) = (medium(&scene, "main"), medium(&scene, "pocket"));
        // The outside, the main interior and 20 pockets.
        assert_eq!(r.num_regions(), 22);
        let line = &scene.interfaces()[0].polyline;
        for j in 0..line.num_segments() {
            let a = line.segment(j).start;
            let s_in = if a.y > 10.0 {
                line.start(j + 1) - 0.01
            } else {
                line.start(j) + 0.01
            };
            let s_out = if a.y > 10.0 {
                line.start(j) + 0.01
            } else {
                line.start(j + 1) - 0.01
            };
            // Both arms of each dip have its pocket on their left.
            let inside = r.sides(0, j, s_in);
            assert_eq!(
                inside,
                Sides {
                    left: pocket,
                    right: main
                },
                "segment {j}"
            );
            let outside = r.sides(0, j, s_out);
            assert_eq!(
                (outside.left, outside.right),
                (pocket, pocket),
                "segment {j}"
            );
            assert_eq!(
                r.region_at(line.point_on(j, s_out) + line.normal(j) * 1e-3),
                Some(0)
            );
        }
    }

    #[test]
    fn interface_along_the_domain_edge() {
        // `top` runs along the domain's top edge and beyond it on both sides.
        let (scene, r) = regions(
            r#"{
            "media": { "upper": { "speed": 1, "at": [5, 8] }, "lower": { "speed": 2, "at": [5, 2] } },
            "domain": [[0, 0], [10, 10]],
            "interfaces": {
                "top": { "points": [[-5, 10], [15, 10]] },
                "middle": { "points": [[0, 5], [10, 5]] }
            },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        let (upper, lower) = (medium(&scene, "upper"), medium(&scene, "lower"));
        assert_eq!(r.num_regions(), 3);
        let top = scene.interface_index("top").unwrap();
        assert_eq!(
            r.sides(top, 0, 2.0),
            Sides {
                left: None,
                right: None
            }
        );
        assert_eq!(
            r.sides(top, 0, 10.0),
            Sides {
                left: None,
                right: upper
            }
        );
        assert_eq!(
            r.sides(top, 0, 18.0),
            Sides {
                left: None,
                right: None
            }
        );
        assert_eq!(r.medium_across(top, 0, 10.0, p(3.0, 11.0)), upper);
        let middle = scene.interface_index("middle").unwrap();
        assert_eq!(
            r.sides(middle, 0, 5.0),
            Sides {
                left: upper,
                right: lower
            }
        );
        assert_eq!(r.region_at(p(5.0, 10.0)), None);
        assert_eq!(r.region_at(p(-1.0, 10.0)), Some(0));
    }

    #[test]
    fn polylines_crossing_at_a_shared_vertex() {
        // Two polylines touch (and cross) at a common vertex: four wedges inside the domain.
        let (scene, r) = regions(
            r#"{
            "media": {
                "n": { "speed": 1, "at": [0, 0.9] }, "e": { "speed": 2, "at": [0.9, 0] },
                "s": { "speed": 3, "at": [0, -0.9] }, "w": { "speed": 4, "at": [-0.9, 0] }
            },
            "domain": [[-1, -1], [1, 1]],
            "interfaces": {
                "a": { "points": [[-1, -1], [0, 0], [1, 1]] },
                "b": { "points": [[-1, 1], [0, 0], [1, -1]] }
            },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        let m = |name| medium(&scene, name);
        assert_eq!(r.num_regions(), 5);
        assert_eq!(r.region_at(p(0.0, 0.0)), None);
        let a = scene.interface_index("a").unwrap();
        let half = scene.interfaces()[a].polyline.start(1);
        assert_eq!(
            r.sides(a, 0, 0.5 * half),
            Sides {
                left: m("w"),
                right: m("s")
            }
        );
        assert_eq!(
            r.sides(a, 1, 1.5 * half),
            Sides {
                left: m("n"),
                right: m("e")
            }
        );
        assert_eq!(r.medium_across(a, 1, 1.5 * half, p(0.0, 0.9)), m("e"));
    }

    #[test]
    fn parallel_lookups_with_hints() {
        use rayon::prelude::*;
        let (scene, r) = regions(
            r#"{
            "media": { "in": { "speed": 1, "at": [0, 0] }, "out": { "speed": 2 } },
            "background": "out",
            "interfaces": { "c": { "points": [[1, 0], [0, 1], [-1, 0], [0, -1]], "closed": true } },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        let (inside, outside) = (medium(&scene, "in"), medium(&scene, "out"));
        let wrong = (0..100_000)
            .into_par_iter()
            .map_init(LocateHint::default, |hint, k| {
                let t = k as f64 * 0.001;
                let q = p(
                    2.0 * t.cos() * (t * 0.37).sin(),
                    2.0 * t.sin() * (t * 0.37).sin(),
                );
                let expected = match (q.x.abs() + q.y.abs()).partial_cmp(&1.0) {
                    Some(std::cmp::Ordering::Less) => inside,
                    Some(std::cmp::Ordering::Greater) => outside,
                    _ => None,
                };
                usize::from(r.medium_at_with_hint(q, hint) != expected)
            })
            .sum::<usize>();
        assert_eq!(wrong, 0);
        assert_eq!(r.medium_at(p(f64::NAN, 0.0)), None);
        assert_eq!(r.medium_at(p(f64::INFINITY, 0.0)), outside);
    }

    #[test]
    fn format_example() {
        let (scene, r) = regions(
            r#"{
            "media": {
                "air":   { "speed": 1.0 },
                "water": { "speed": 0.75, "at": [0.5, -0.5] }
            },
            "background": "air",
            "domain": [[-2.0, -3.0], [5.0, 3.0]],
            "interfaces": {
                "surface": { "points": [[-2.0, 0.0], [5.0, 0.0]] },
                "lens":    { "points": [[3, 0.5], [4, 0.5], [4, 1.5]], "closed": true }
            },
            "sources":   [[0.0, 1.0]],
            "receivers": [[1.0, -1.0], [0.5, -1.0]],
            "paths": [{ "name": "transmitted", "steps": [{ "refract": "surface" }] }]
        }"#,
        );
        let (air, water) = (medium(&scene, "air"), medium(&scene, "water"));
        // Outside, above the surface, in the (unclaimed) lens, below the surface.
        assert_eq!(r.num_regions(), 4);
        assert_eq!(r.medium_at(p(0.0, 1.0)), air);
        assert_eq!(r.medium_at(p(3.9, 0.6)), air);
        assert_ne!(r.region_at(p(3.9, 0.6)), r.region_at(p(0.0, 1.0)));
        assert_eq!(r.medium_at(p(1.0, -1.0)), water);
        assert_eq!(r.medium_at(p(10.0, 10.0)), air);
        let surface = scene.interface_index("surface").unwrap();
        assert_eq!(
            r.sides(surface, 0, 2.0),
            Sides {
                left: air,
                right: water
            }
        );
        assert_eq!(r.medium_across(surface, 0, 2.0, p(0.0, 1.0)), water);
        assert_eq!(r.medium_across(surface, 0, 2.0, p(1.0, -1.0)), air);
        assert_eq!(r.medium_across(surface, 0, 2.0, p(7.0, 0.0)), None);
    }

    #[test]
    fn two_at_in_one_region() {
        let scene = Scene::from_json(
            r#"{
            "media": {
                "a": { "speed": 1, "at": [0, 1] },
                "b": { "speed": 2, "at": [3, 2] }
            },
            "interfaces": { "s": { "points": [[-1, 0], [1, 0]] } },
            "sources": [], "receivers": [], "paths": []
        }"#,
        )
        .unwrap();
        let e = Regions::build(&scene).unwrap_err();
        assert_eq!(e.key, "media.b.at");
        assert_eq!(
            e.message,
            "lies in the same region as media.a.at (without a `domain`, an open interface \
             divides nothing: add a `domain` box whose edges the interfaces end on)"
        );
    }

    #[test]
    fn at_on_the_domain_edge() {
        let scene = Scene::from_json(
            r#"{
            "media": { "a": { "speed": 1, "at": [0, 1] } },
            "domain": [[0, 0], [1, 1]],
            "sources": [], "receivers": [], "paths": []
        }"#,
        )
        .unwrap_err();
        assert_eq!(scene.key, "media.a.at");
        assert!(scene.message.contains("edge of the domain"), "{scene}");
    }

    #[test]
    fn t_junction() {
        // A vertical fault ends on the interior of a horizontal layer boundary.
        let (scene, r) = regions(
            r#"{
            "media": {
                "top": { "speed": 1, "at": [0, 5] },
                "left": { "speed": 2, "at": [-3, -5] },
                "right": { "speed": 3, "at": [3, -5] }
            },
            "domain": [[-10, -10], [10, 10]],
            "interfaces": {
                "layer": { "points": [[-10, 0], [10, 0]] },
                "fault": { "points": [[0, 0], [0, -10]] }
            },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        let (top, west, east) = (
            medium(&scene, "top"),
            medium(&scene, "left"),
            medium(&scene, "right"),
        );
        assert_eq!(r.num_regions(), 4);
        assert_eq!(r.medium_at(p(-9.0, -1.0)), west);
        assert_eq!(r.medium_at(p(9.0, -9.0)), east);
        assert_eq!(r.medium_at(p(0.0, 0.5)), top);
        assert_eq!(r.region_at(p(0.0, -5.0)), None);
        assert_eq!(r.region_at(p(0.0, 0.0)), None);
        let layer = scene.interface_index("layer").unwrap();
        // The one segment is two pieces, split at arclength 10 by the fault's end.
        assert_eq!(
            r.sides(layer, 0, 3.0),
            Sides {
                left: top,
                right: west
            }
        );
        assert_eq!(
            r.sides(layer, 0, 9.999),
            Sides {
                left: top,
                right: west
            }
        );
        assert_eq!(
            r.sides(layer, 0, 10.001),
            Sides {
                left: top,
                right: east
            }
        );
        assert_eq!(
            r.sides(layer, 0, 17.0),
            Sides {
                left: top,
                right: east
            }
        );
        assert_eq!(r.medium_across(layer, 0, 3.0, p(-3.0, 4.0)), west);
        assert_eq!(r.medium_across(layer, 0, 13.0, p(-3.0, 4.0)), east);
        assert_eq!(r.medium_across(layer, 0, 13.0, p(-3.0, -4.0)), top);
        let fault = scene.interface_index("fault").unwrap();
        // Downwards: the normal points to +x.
        assert_eq!(
            r.sides(fault, 0, 4.0),
            Sides {
                left: east,
                right: west
            }
        );
        assert_eq!(r.medium_across(fault, 0, 4.0, p(-1.0, 0.0)), east);
        assert_eq!(r.medium_across(fault, 0, 4.0, p(1.0, -20.0)), west);
    }

    #[test]
    fn t_junction_inserted_the_other_way() {
        // Without a domain: a bar (running right to left, with a vertex of its own) and an open
        // box close a rectangle; a stem joins the interiors of a box segment and a bar segment.
        let (scene, r) = regions(
            r#"{
            "media": {
                "above": { "speed": 1, "at": [0, 1] },
                "west": { "speed": 2, "at": [-1, -1] },
                "east": { "speed": 3, "at": [1, -1] }
            },
            "interfaces": {
                "a_bar": { "points": [[2, 0], [0.5, 0], [-2, 0]] },
                "b_box": { "points": [[-2, 0], [-2, -3], [2, -3], [2, 0]] },
                "c_stem": { "points": [[0, -3], [0, 0]] }
            },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        let m = |n| medium(&scene, n);
        assert_eq!(r.num_regions(), 3);
        assert_eq!(r.medium_at(p(-0.1, -0.1)), m("west"));
        assert_eq!(r.medium_at(p(0.1, -2.9)), m("east"));
        assert_eq!(r.medium_at(p(0.0, 0.1)), m("above"));
        assert_eq!(r.medium_at(p(0.0, -5.0)), m("above"));
        let bar = scene.interface_index("a_bar").unwrap();
        // Segment 1 runs from (0.5, 0) to (-2, 0), leftwards: its normal points down.
        let line = &scene.interfaces()[bar].polyline;
        assert_eq!(
            r.sides(bar, 1, line.start(1) + 0.25),
            Sides {
                left: m("east"),
                right: m("above")
            }
        );
        assert_eq!(
            r.sides(bar, 1, line.start(1) + 1.0),
            Sides {
                left: m("west"),
                right: m("above")
            }
        );
        assert_eq!(
            r.sides(bar, 0, 1.0),
            Sides {
                left: m("east"),
                right: m("above")
            }
        );
        let bx = scene.interface_index("b_box").unwrap();
        // Segment 1 runs from (-2, -3) to (2, -3): its normal points up, into the box.
        assert_eq!(
            r.sides(bx, 1, 3.0 + 1.0),
            Sides {
                left: m("west"),
                right: m("above")
            }
        );
        assert_eq!(
            r.sides(bx, 1, 3.0 + 3.0),
            Sides {
                left: m("east"),
                right: m("above")
            }
        );
    }

    #[test]
    fn closed_polygon_without_domain() {
        let (scene, r) = regions(
            r#"{
            "media": {
                "glass": { "index": 1.5, "at": [0.2, 0.2] },
                "air": { "index": 1.0 }
            },
            "background": "air",
            "interfaces": { "lens": { "points": [[0, 0], [1, 0], [1, 1], [0, 1]], "closed": true } },
            "sources": [[-5, 0.5]], "receivers": [], "paths": []
        }"#,
        );
        let (glass, air) = (medium(&scene, "glass"), medium(&scene, "air"));
        assert_eq!(r.num_regions(), 2);
        assert_eq!(r.medium_at(p(0.5, 0.5)), glass);
        assert_eq!(r.medium_at(p(0.99, 0.01)), glass);
        assert_eq!(r.medium_at(p(1.01, 0.5)), air);
        assert_eq!(r.medium_at(p(-5.0, 0.5)), air);
        assert_eq!(r.medium_at(p(1e6, -1e9)), air);
        assert_eq!(r.medium_at(p(1e300, 1e300)), air);
        assert_eq!(r.medium_at(p(1.0, 0.5)), None);
        // Counter-clockwise polygon: the normal points inwards.
        for j in 0..4 {
            let s = j as f64 + 0.5;
            assert_eq!(
                r.sides(0, j, s),
                Sides {
                    left: glass,
                    right: air
                }
            );
        }
        assert_eq!(r.medium_across(0, 3, 3.5, p(-1.0, 0.5)), glass);
        assert_eq!(r.medium_across(0, 3, 3.5, p(0.5, 0.5)), air);
        // At the corner (1, 1), where the top segment starts: from (2, 0.5), below the top's
        // line but outside the square, the sum of the two normals says outside, so glass lies
        // across (the top's line alone would say air); from inside, air. The same corner as the
        // end of the right-hand segment, and the corner (0, 0) where the polygon closes.
        assert_eq!(r.medium_across(0, 2, 2.0, p(2.0, 0.5)), glass);
        assert_eq!(r.medium_across(0, 1, 2.0, p(2.0, 0.5)), glass);
        assert_eq!(r.medium_across(0, 2, 2.0, p(0.5, 0.9)), air);
        assert_eq!(r.medium_across(0, 0, 0.0, p(0.5, -2.0)), glass);
        assert_eq!(r.medium_across(0, 3, 4.0, p(0.5, -2.0)), glass);
    }

    #[test]
    fn open_polyline_without_domain_divides_nothing() {
        let (scene, r) = regions(
            r#"{
            "media": { "a": { "speed": 1, "at": [0, 1] } },
            "interfaces": { "s": { "points": [[-1, 0], [1, 0]] } },
            "sources": [], "receivers": [], "paths": []
        }"#,
        );
        assert_eq!(r.num_regions(), 1);
        assert_eq!(r.medium_at(p(0.0, -1.0)), medium(&scene, "a"));
        // On the polyline, but it separates nothing.
        assert_eq!(r.medium_at(p(0.0, 0.0)), medium(&scene, "a"));
        assert_eq!(
            r.sides(0, 0, 1.0),
            Sides {
                left: medium(&scene, "a"),
                right: medium(&scene, "a")
            }
        );
    }

    #[test]
    fn shared_vertices_and_extreme_coordinates() {
        // Two interfaces share both end vertices, and coordinates spade cannot take directly.
        for k in [1e-98, 1e-30, 1.0, 1e40, 1e70] {
            let json = format!(
                r#"{{
                "media": {{ "in": {{ "speed": 1, "at": [{a}, {b}] }}, "out": {{ "speed": 2 }} }},
                "background": "out",
                "interfaces": {{
                    "upper": {{ "points": [[0, 0], [{k}, {k}], [{two}, 0]] }},
                    "lower": {{ "points": [[0, 0], [{k}, {mk}], [{two}, 0]] }}
                }},
                "sources": [], "receivers": [], "paths": []
            }}"#,
                a = k,
                b = 0.1 * k,
                two = 2.0 * k,
                mk = -k,
            );
            let (scene, r) = regions(&json);
            let (inside, outside) = (medium(&scene, "in"), medium(&scene, "out"));
            assert_eq!(r.num_regions(), 2, "k = {k}");
            assert_eq!(r.medium_at(p(k, -0.5 * k)), inside, "k = {k}");
            assert_eq!(r.medium_at(p(k, 1.5 * k)), outside, "k = {k}");
            assert_eq!(r.medium_at(p(-k, 0.0)), outside, "k = {k}");
            let upper = scene.interface_index("upper").unwrap();
            let s = 0.5 * scene.interfaces()[upper].polyline.start(1);
            assert_eq!(
                r.sides(upper, 0, s),
                Sides {
                    left: outside,
                    right: inside
                },
                "k = {k}"
            );
        }
    }

    #[test]
    fn no_interfaces() {
        // No medium anywhere: refused.
        let scene = Scene::from_json(
            r#"{ "media": { "a": { "speed": 1 } }, "sources": [], "receivers": [], "paths": [] }"#,
        )
        .unwrap();
        assert_eq!(Regions::build(&scene).unwrap_err().key, "background");
        let (_, r) = regions(
            r#"{ "media": { "a": { "speed": 1 } }, "background": "a",
                 "sources": [], "receivers": [], "paths": [] }"#,
        );
        assert_eq!(r.num_regions(), 1);
        assert_eq!(r.medium_at(p(0.0, 0.0)), Some(0));
        let (scene, r) = regions(
            r#"{ "media": { "a": { "speed": 1, "at": [0.5, 0.5] } }, "domain": [[0, 0], [1, 1]],
                 "sources": [], "receivers": [], "paths": [] }"#,
        );
        assert_eq!(r.num_regions(), 2);
        assert_eq!(r.medium_at(p(0.2, 0.9)), medium(&scene, "a"));
        assert_eq!(r.medium_at(p(2.0, 0.9)), None);
    }

    #[test]
    fn sea_floor_100k_segments() {
        let n = 100_000;
        let pts: Vec<String> = (0..=n)
            .map(|i| {
                let x = -50.0 + 100.0 * i as f64 / n as f64;
                format!("[{x}, {}]", 0.1 * (x * 7.3).sin())
            })
            .collect();
        let json = format!(
            r#"{{
            "media": {{ "water": {{ "speed": 1.5, "at": [3, 5] }}, "rock": {{ "speed": 3, "at": [3, -5] }} }},
            "domain": [[-50, -10], [50, 10]],
            "interfaces": {{ "floor": {{ "points": [{}] }} }},
            "sources": [], "receivers": [], "paths": []
        }}"#,
            pts.join(",")
        );
        let scene = Scene::from_json(&json).unwrap();
        let r = Regions::build(&scene).unwrap();
        let (water, rock) = (medium(&scene, "water"), medium(&scene, "rock"));
        assert_eq!(r.num_regions(), 3);
        let mut hint = LocateHint::default();
        for k in 0..1000 {
            let x = -49.9 + 0.0998 * k as f64;
            let y = 0.1 * (x * 7.3).sin();
            assert_eq!(r.medium_at(p(x, y + 0.01)), water, "x = {x}");
            assert_eq!(r.medium_at(p(x, y - 0.01)), rock, "x = {x}");
            assert_eq!(
                r.medium_at_with_hint(p(x, 9.0), &mut hint),
                water,
                "x = {x}"
            );
            assert_eq!(
                r.medium_at_with_hint(p(x, -9.0), &mut hint),
                rock,
                "x = {x}"
            );
        }
        let line = &scene.interfaces()[0].polyline;
        for j in (0..n).step_by(997) {
            let s = 0.5 * (line.start(j) + line.start(j + 1));
            assert_eq!(
                r.sides(0, j, s),
                Sides {
                    left: water,
                    right: rock
                },
                "segment {j}"
            );
            let q = line.point_on(j, s) + line.normal(j);
            assert_eq!(r.medium_across(0, j, s, q), rock);
            assert_eq!(
                r.medium_across(0, j, s, line.point_on(j, s) - line.normal(j)),
                water
            );
        }
    }

    #[test]
    fn long_polylines_build() {
        // Spade's bulk loading and insertion in polyline order are quadratic on these.
        let n = 100_000;
        type Shape = fn(f64) -> (f64, f64);
        let shapes: [(&str, Shape); 3] = [
            ("straight", |t| (-50.0 + 100.0 * t, 0.0)),
            ("gentle", |t| (-50.0 + 100.0 * t, 5.0 * (t * 7.3).sin())),
            ("diagonal", |t| (-50.0 + 100.0 * t, -10.0 + 20.0 * t)),
        ];
        for (name, f) in shapes {
            let pts: Vec<String> = (0..=n)
                .map(|i| {
                    let (x, y) = f(i as f64 / n as f64);
                    format!("[{x}, {y}]")
                })
                .collect();
            let json = format!(
                r#"{{
                "media": {{ "up": {{ "speed": 1, "at": [-49, 9.9] }}, "down": {{ "speed": 2, "at": [49, -9.9] }} }},
                "domain": [[-50, -10], [50, 10]],
                "interfaces": {{ "i": {{ "points": [{}] }} }},
                "sources": [], "receivers": [], "paths": []
            }}"#,
                pts.join(",")
            );
            let scene = Scene::from_json(&json).unwrap();
            let r = Regions::build(&scene).unwrap();
            assert_eq!(r.num_regions(), 3, "{name}");
            let line = &scene.interfaces()[0].polyline;
            for j in (0..n).step_by(1009) {
                let s = 0.5 * (line.start(j) + line.start(j + 1));
                let sides = r.sides(0, j, s);
                assert_eq!(
                    sides,
                    Sides {
                        left: medium(&scene, "up"),
                        right: medium(&scene, "down")
                    },
                    "{name} {j}"
                );
            }
        }
    }

    #[test]
    fn send_sync() {
        fn check<T: Send + Sync>() {}
        check::<Regions>();
        check::<LocateHint>();
    }
}
