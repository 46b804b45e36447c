// maps.h: the four maps of one camera, in memory, in the layout the simulation
// and the gather read (docs/design.md section 2).
//
// Row 0 is the top scanline (EXR order): texel (i, j) is at index j*width + i.
// Depth holds +inf where there is no surface (NaN, d <= 0 and d >= 1e30 in a file
// are turned into +inf on loading).
#ifndef WX_MAPS_H
#define WX_MAPS_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "core/limits.h"
#include "model/image.h"
#include "model/scene.h"

typedef struct wx_maps {
    int width;
    int height;
    /// Layers (docs/design.md section 14; 0 or 1: one): every plane below
    /// holds one block per layer, layer k after layer k-1: depth at
    /// k*W*H, normal at 3*k*W*H, impact at 2*k*W*H, the substance planes
    /// (dirt, deposit, erosion, initial_dirt) at k*S*W*H, the others at k*W*H.
    /// Layer 0 is the first surface each texel's view ray meets, layer k the
    /// (k+1)-th crossing, front- or back-facing; a layer with no crossing left
    /// holds depth +inf. With more than one layer every normal points out of
    /// the solid (so n.view > 0 where the ray leaves it); with one, it faces
    /// the camera as version 2's maps do.
    int layers;
    /// The normals point out of the solid (the maps of a layered camera and
    /// its layer views); false: they face the camera (one layer).
    bool outward;
    float *depth;   ///< width*height, d or +inf
    float *normal;  ///< 3*width*height, interleaved x y z, world space, unit
    float *impact;  ///< 2*width*height, interleaved absorption, bounce
    /// The dirt planes hold `substances` planes of width*height one after the
    /// other (substance s at s*width*height; docs/design.md section 9): with
    /// one substance, version 1's single planes.
    int substances; ///< 0 or 1: one substance
    float *dirt;    ///< amount of each substance on the texel's surface patch
    float *deposit; ///< deposit fraction
    float *erosion; ///< erosion fraction
    /// What a simulation adds, for the gather (NULL when the dirt map holds no
    /// simulation: a baked or given map): per substance, the amount the surface
    /// would hold without the particles (the initial amount aged by the rules),
    /// and the impacts that exchanged dirt at each texel.
    float *initial_dirt; ///< substances planes
    float *hits;         ///< width*height
    /// What the bake records for ageing (NULL when not recorded): the global
    /// index + 1 of the <Surface> each texel shows (0: none), and the surface
    /// area the texel owns (texel area / |N.view| where this camera sees the
    /// point most head-on, else 0), which Grow multiplies.
    float *surface; ///< width*height
    float *area;    ///< width*height
    /// The share of each texel's surface this camera owns (model/ownership.h:
    /// it sees it most head-on, so the deposits there are stored here): what
    /// the gather divides by. Computed in memory once the maps are read
    /// (pipeline/load.c), never written; NULL until then.
    float *owned;   ///< width*height
    /// A layer view of a layered camera (wx_maps_layer_view): the camera's
    /// depth and normal planes of every layer as baked (before wx_maps_bury),
    /// borrowed, and which of them this view is, so a point is told from the
    /// other crossings of its texel (wx_crossing_nearer). NULL otherwise.
    const float *crossing_depth, *crossing_normal;
    int crossing_layers, crossing_layer;
    /// The dirt map file's header attributes (camera matrices, name), kept so
    /// that the simulated dirt map is written with them without reading the
    /// file again.
    int dirt_attr_count;
    wx_attr *dirt_attrs;
} wx_maps;

/// Name of the channel in which a simulated dirt map counts each texel's hits.
#define WX_HITS_CHANNEL "hits"

/// Name of the channel in which a simulated dirt map keeps its initial dirt.
#define WX_INITIAL_DIRT_CHANNEL "initialDirt"

/// Names of the channels in which the bake records each texel's <Surface> and
/// the area Grow multiplies (model/maps.h).
#define WX_SURFACE_CHANNEL "surface"
#define WX_AREA_CHANNEL "area"

/// The channels of a dirt map of `scene` (docs/design.md section 9), in the
/// order of wx_maps' planes: without declared substances version 1's R, G, B
/// (then initialDirt and hits once `simulated`); with them, per substance
/// NAME.amount, NAME.deposit, NAME.erosion (then NAME.initial per substance
/// and hits once simulated). Then "surface" when some surface has rules of
/// its own, and "area" when a rule grows. Returns the count (at most
/// WX_IMAGE_MAX_CHANNELS).
int wx_dirt_channels(const wx_scene *scene, bool simulated, char names[][WX_NAME_MAX]);

/// Frees every plane; the struct is zeroed.
void wx_maps_free(wx_maps *maps);

/// Layers the planes hold (at least 1).
static inline int wx_maps_layers(const wx_maps *maps)
{
    return maps->layers > 1 ? maps->layers : 1;
}

/// A view of layer `layer` of `maps`: a wx_maps of one layer whose planes point
/// into that layer's blocks (borrowed: never pass it to wx_maps_free; it lives
/// as long as `maps`). The header attributes are shared too.
void wx_maps_layer_view(const wx_maps *maps, int layer, wx_maps *view);

/// What a crossing of a layered texel bounds, once its crossings are reduced
/// to the outline of its solids (wx_layers_outline).
enum {
    WX_OUTLINE_NONE = 0,
    WX_OUTLINE_ENTER = 1, ///< enters a solid the next kept crossing (LEAVE) leaves
    WX_OUTLINE_LEAVE = 2,
    WX_OUTLINE_SHEET = 3, ///< one-sided: nothing closes it (a pane, an open sheet)
    WX_OUTLINE_TAIL = 4,  ///< solid from here on: behind the last layer is unknown
};

/// The outline of one texel's solids from its n crossings, nearest first, of
/// K layers (docs/physics.md, "Layered maps"): each leaving crossing closes
/// the nearest entering one still open (solids nest: a roof's slab inside a
/// wall, a sill through a facade); what no crossing closes is a sheet or,
/// when every layer holds a crossing, the start of a solid whose end lies
/// beyond them (TAIL; then also a last crossing that leaves: what is behind it
/// is unknown, so solid, as one layer's map says). Nested and overlapping
/// solids merge into one interval; the faces and sheets inside it are
/// dropped. Writes the kept crossings' kinds and indices into kind[], from[]
/// (nearest first); returns how many.
int wx_layers_outline(const bool *entering, int n, int K, uint8_t *kind, uint8_t *from);

/// Whether a point at depth dp of surface normal n, which layer `layer` of
/// texel t holds within its tolerance, lies strictly nearer another crossing
/// of that texel whose normal is on the same side as n (depth and normal:
/// `layers` planes of `texels`, as baked): then it is that crossing's surface
/// (the wall 1 mm behind a pane, not the pane), and the layer does not hold
/// it. False without crossings.
bool wx_crossing_nearer(const float *depth, const float *normal, int layers, int layer,
                        size_t texels, size_t t, float dp, const float n[3]);

/// The depth planes of `maps` (every layer) into `depth`, with the crossings
/// buried inside a solid (those wx_layers_outline drops: a slab's face inside
/// the wall it runs into; in a full stack, every crossing after the entering
/// face of a solid left open, which runs on behind the last layer) or sealed
/// by contact (two solids' faces less than `sheet`, in d, apart: a wall
/// behind the glass that touches it, a house's underside on the ground; a
/// solid's face that close behind a pane facing the camera) made +inf, so
/// that no view sees them: nothing can reach them. `view` is the camera's
/// unit viewing direction. One layer: a copy.
void wx_maps_bury(const wx_maps *maps, const float view[3], float sheet, float *depth);

/// The file channel of `channel` in layer `layer` (docs/design.md section 14):
/// the name itself in layer 0, "layerK.NAME" in layer K >= 1. Returns false
/// when the name does not fit WX_NAME_MAX.
bool wx_layer_channel(char out[WX_NAME_MAX], int layer, const char *channel);

/// Substances the dirt planes hold (at least 1).
static inline int wx_maps_substances(const wx_maps *maps)
{
    return maps->substances > 1 ? maps->substances : 1;
}

/// True when a stored depth value means "no surface" (NaN, <= 0, >= 1e30, inf).
static inline bool wx_depth_is_empty(float d)
{
    return !(d > 0.0f && d < 1e30f);
}

#endif
