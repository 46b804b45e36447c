// collider.h: the projected-maps collider (thesis 4.8.4.1, docs/design.md section 4).
//
// The geometry is known only through the depth maps of the input cameras. A
// point collides when at least one camera sees it inside its frame and every
// camera that does says it lies behind its surface (d > depth); a texel with no
// surface says "not behind". A step is a segment, and the collider finds the
// first point of the segment that collides (the swept test): for each camera it
// walks the segment through the map half a texel at a time and solves, in each
// half-texel, where the segment passes behind the surface; the cameras' answers
// are intersected by leapfrogging from one to the next. So a particle never
// passes through a surface that a map records, however fast it flies.
//
// Depth between texel centres is bilinear when the four texels around the
// point all hold a surface (a smooth surface: no terraces, no banding, thesis
// 5.1.2), plus second-order terms where the normals say the surface curves
// (collider_build.c, curve_cells), and the texel's own depth otherwise
// (silhouettes, the thesis' nearest-texel rule everywhere when `nearest` is
// set).
//
// A camera with layered maps (wx_maps.layers = K > 1, docs/design.md section
// 14) records each texel's first K crossings with outward normals; it says
// "behind" only inside the solid intervals and thin-sheet slabs they bound
// (docs/physics.md, "Layered maps"), so the space behind a railing or under an
// overhang is free. A camera with one layer works exactly as before.
//
// A conservative coarse test answers most steps without the walk: per camera a
// pyramid of minimum depths over 3x3 blocks around each block proves that a short
// segment stays in front of every surface near it.
#ifndef WX_COLLIDER_H
#define WX_COLLIDER_H

#include <stdbool.h>
#include <stdint.h>

#include "model/camera.h"
#include "core/error.h"
#include "core/limits.h"
#include "model/maps.h"

/// Levels of the coarse pyramid: blocks of 4, 16, 64, ... texels.
#define WX_COARSE_LEVELS 5 ///< collider.c writes the five levels out one by one
#define WX_COARSE_BLOCK_SHIFT 2
#define WX_COARSE_LEVEL_SHIFT 2

/// One input camera as the collider sees it.
typedef struct wx_collider_camera {
    int width;
    int height;
    /// Texel space: X = u*W, Y = (1-v)*H (texel (i, j) covers [i, i+1) x [j, j+1)),
    /// D = d. X = x*mx[0] + y*mx[1] + z*mx[2] + mx[3], likewise Y and D.
    double mx[4], my[4], md[4];
    float fmx[4], fmy[4], fmd[4]; ///< the same in float, for the coarse test
    float back[3];  ///< world displacement that lowers d by 1 and keeps u, v
    float texel_ws; ///< world size of the smaller side of a texel
    /// layers*W*H (layer k at k*W*H; layer 0 is today's map), +inf where there
    /// is no surface (owned copy; with layers, each crossing moved out by its
    /// margin: collider_build.c, widen_crossings)
    float *depth;
    const float *normal; ///< 3*layers*W*H world normals (borrowed)
    const float *impact; ///< 2*layers*W*H absorption, bounce (borrowed)
    /// Layered maps (docs/physics.md, "Layered maps"): 1, or the K > 1 crossings
    /// each texel records. With one layer everything behind the surface is
    /// solid and `role` is NULL; with more, role[k*W*H + t] says what crossing
    /// k of texel t bounds (WX_ROLE_* in collider.c, plus a bit for its
    /// facing), and a one-sided crossing is a slab `sheet` thick (in d).
    int layers;
    uint8_t *role;
    /// With layers: the crossings a solid's outline needs, nearest first
    /// (collider.c classify_layers: the faces inside overlapping solids left
    /// out), so depth[k*W*H + t] is the k-th of them and origin[k*W*H + t] the
    /// layer of the maps (normal, impact, the hit's layer) it came from.
    uint8_t *origin;
    double sheet;
    /// Second-order cells (docs/physics.md, "Depth between texels";
    /// collider_build.c, curve_cells): per layer and texel t, the curvatures
    /// (a, b) along X and Y of the bilinear cell whose first corner is t, in
    /// units of `curve_unit` (depth per texel squared); the cell's depth is
    /// then bilinear + a/2 fx (fx - 1) + b/2 fy (fy - 1). NULL when no cell of
    /// the camera curves (planes).
    int16_t *curve;
    double curve_unit;
    /// The farthest any curved cell dips in front of its corners (0 without
    /// curved cells); the coarse pyramid and near3 are lowered texel by texel.
    double bulge_most;
    /// Coarse pyramid: level l has blocks of 4 << 2l texels; its value at block
    /// (bx, by) is the least depth over the 3x3 blocks around it, lowered by a
    /// rounding margin. Levels are stored one after the other in `coarse`.
    int levels;
    int level_width[WX_COARSE_LEVELS];
    int level_height[WX_COARSE_LEVELS];
    int level_offset[WX_COARSE_LEVELS];
    float *coarse;
    /// Per texel, the least first-crossing depth over the 3 x 3 texels around
    /// it (every texel a swept test reads for a point in that texel), lowered
    /// by the pyramid's rounding margin and, where one of those texels holds a
    /// sheet seen from behind (whose slab starts a sheet in front of its
    /// crossing), by a sheet: a segment in front of it over each texel it
    /// crosses is free for this camera (wx_collider_fine_clear).
    float *near3;
    /// No texel on the map's border records a surface: the model lies inside
    /// this camera's frame, so outside the frame it sees no surface, as over a
    /// texel with none, and a point there does not collide (docs/physics.md,
    /// "Cameras that frame the model").
    bool frames_model;
    /// Fills (docs/physics.md, "Surfaces a camera sees edge-on"): where this
    /// camera missed a surface another records, solid over that stretch of its
    /// ray and no surface. With one layer fill[t] marks a texel whose depth is
    /// such a fill (NULL when there is none); with layers the role's
    /// WX_ROLE_FILL bit does. fill_texels counts the texels that got one.
    uint8_t *fill;
    int64_t fill_texels;
} wx_collider_camera;

typedef struct wx_collider {
    int camera_count;
    wx_collider_camera *cameras;
    bool nearest; ///< nearest-texel depth everywhere (the thesis' rule)
    /// With layered maps: the largest texel (world units) of any camera. A
    /// point collides where every camera that sees it agrees; with layers a
    /// camera seeing a wall edge-on vouches for it only from its own texel's
    /// edge, so the hit may lie up to a texel of that camera behind the face
    /// the head-on camera records, and pick_camera allows that much more
    /// (0 with one layer everywhere: today's rule).
    double layered_slack;
    /// A view of another collider (wx_collider_view): its planes are that
    /// one's, and wx_collider_free frees only the cameras array.
    bool view;
} wx_collider;

/// Builds the collider over `count` cameras and their maps (depth, normal and
/// impact are needed; normal and impact are borrowed and must outlive the
/// collider). Fails (WX_BAD_INPUT) on a projective (non-orthographic) matrix, a
/// map whose size differs from the camera's, or too many cameras.
wx_result wx_collider_init(wx_collider *collider, const wx_camera *cameras, const wx_maps *maps,
                           int count, bool nearest, wx_error *err);

/// A tile's collider (docs/tiles.md): particles live only within the box
/// [lo, hi] (the tile and its halo), and `weathering tiles` cut each camera's
/// frame to the box's image. Each camera then frames the model when its map
/// holds no surface on the border of the sides the box reaches beyond (the
/// whole camera's own sides); the sides cut to the box have only space
/// outside the box beyond them, so a surface cut there no longer makes the
/// camera say "no information" outside its frame. Without this, a point
/// outside a cut camera's frame lost the whole camera's "free space there",
/// and another camera (a top camera, solid below its first surface) could
/// catch it: rain falling past a slab's edge was caught under the slab.
void wx_collider_frame_box(wx_collider *collider, const double lo[3], const double hi[3]);

/// The collider `shared` with the hits reading maps[c].impact (absorption,
/// bounce) for camera c: the same geometry, every plane borrowed from `shared`
/// (which must outlive the view, and be built over the same cameras, with
/// maps[c]'s size and layers). A run builds one collider for its derived masks
/// and its simulation this way (pipeline/run.c): the masks need no impact.
wx_result wx_collider_view(wx_collider *view, const wx_collider *shared, const wx_maps *maps,
                           wx_error *err);

/// Frees what the collider owns; the struct is zeroed.
void wx_collider_free(wx_collider *collider);

/// The first collision along a segment.
typedef struct wx_hit {
    float s;          ///< segment parameter of the hit, in [0, 1]
    int camera;       ///< the camera that gives the hit (smallest d - depth)
    int layer;        ///< the layer of that camera's maps that holds the surface hit
    uint32_t texel;   ///< j*W + i in that camera's maps (of that layer)
    float point[3];   ///< world point where the segment enters the surface
    /// Where the particle is put back: on that camera's surface slightly in
    /// front of it (with layers: on the hit face's free side), or, when it
    /// entered through a silhouette or frame edge, just back along its segment;
    /// never a colliding point unless the segment started inside.
    float front[3];
    /// Unit world normal at the texel (with layers: the hit face's, turned to
    /// face the particle when it points along the segment, a sheet hit from
    /// behind).
    float normal[3];
    float absorption; ///< impact R
    float bounce;     ///< impact G
} wx_hit;

/// Swept test of the segment p0 -> p1: true and the first colliding point when
/// there is one. If p0 itself collides (a particle emitted inside the geometry),
/// the hit is at s = 0.
bool wx_collider_sweep(const wx_collider *collider, const float p0[3], const float p1[3],
                       wx_hit *hit);

/// How far a slide goes back in front of a bump of the collision surface
/// (sim/step.c, rest_of_step; docs/physics.md, "Bumps"): `climb` texels of
/// the contact's camera `cam` along the contact's unit normal `n`, towards the
/// side of the surface that camera sees; into `out`. Square to the surface,
/// so the lift moves the particle off it, never along it.
void wx_collider_bump_lift(const wx_collider_camera *cam, const float n[3], float climb,
                           float out[3]);

/// The point rule of docs/design.md section 4 for one point (no sweep).
bool wx_collider_point_collides(const wx_collider *collider, const float p[3]);

/// Camera c's part of that rule at texel-space (X, Y, D) inside its frame: it
/// may collide there (behind its surface, or inside one of its solids).
/// wx_collider_point_collides asks it of every camera whose frame holds the
/// point (tests/tools/surface_probe.c names the cameras that say no).
bool wx_collider_camera_may_collide(const wx_collider *collider, int c, double X, double Y,
                                    double D);

/// Coarse test of WX_PARTICLE_BLOCK segments (x0, y0, z0) -> (x1, y1, z1) against
/// the `count` cameras listed in `cams`: bit k of the result is set when one of
/// them sees all of segment k in front of its surfaces (then it cannot collide);
/// bit k of *outside when segment k lies outside the frames of all of them (it
/// cannot collide when that holds for every camera of the collider). The test
/// stops once every lane is cleared (then *outside is meaningless): any order
/// gives the same clearing, a good one (the camera that clears most first) is
/// faster. When `credit` is not NULL, credit[c] counts the lanes camera c
/// cleared first.
uint32_t wx_collider_coarse_block(const wx_collider *collider, const int *cams, int count,
                                  uint32_t *restrict credit, const float *restrict x0,
                                  const float *restrict y0, const float *restrict z0,
                                  const float *restrict x1, const float *restrict y1,
                                  const float *restrict z1, uint32_t *restrict outside);

/// The coarse test of one segment: true when it certainly does not collide.
bool wx_collider_coarse_clear(const wx_collider *collider, const float p0[3], const float p1[3]);

/// The fine test of one segment, for segments the coarse test leaves: walks
/// each camera's texels along the segment's projection and returns true when
/// one camera sees the whole segment inside its frame and in front of `near3`
/// over every texel it crosses. Then the swept test finds no hit (that camera
/// says "in front" everywhere), so it need not run; it never clears a segment
/// the swept test would stop (docs/physics.md, "Fine test").
bool wx_collider_fine_clear(const wx_collider *collider, const float p0[3], const float p1[3]);

/// Asks the memory system for the depth texels a swept test near p will read
/// (a hint: it changes no result).
void wx_collider_prefetch(const wx_collider *collider, const float p[3]);

/// Depth of the collider's surface at texel-space point (X, Y) of camera c (the
/// bilinear or nearest rule above; layer 0, the first crossing, with layered
/// maps); +inf where there is no surface or outside.
double wx_collider_depth_at(const wx_collider *collider, int c, double X, double Y);

#endif
