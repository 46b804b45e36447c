// scene.h: the scene as data (docs/design.md section 3): solver, force fields,
// emitters, collider, cameras with their maps and outputs, meshes with their
// surfaces. Plain structures with their defaults; io/scene_xml.c fills them
// from a scene file and checks everything, so later phases can trust them.
#ifndef WX_SCENE_H
#define WX_SCENE_H

#include <stdbool.h>
#include <stdint.h>

#include "core/error.h"
#include "core/limits.h"
#include "model/camera.h"

typedef enum wx_field_kind {
    WX_FIELD_GRAVITY,    ///< acceleration along -Y
    WX_FIELD_WIND,       ///< force = strength * unit(dir)
    WX_FIELD_TURBULENCE, ///< force from Perlin's simplex noise of (position, time)
} wx_field_kind;

typedef struct wx_field {
    wx_field_kind kind;
    float strength;  ///< Gravity: acceleration (m/s^2); Wind, Turbulence: force
    float dir[3];    ///< Wind: unit direction (normalised on loading)
    float frequency; ///< Turbulence: frequency of the first octave, 1/m in space and 1/s in time
    int octaves;     ///< Turbulence: number of octaves, 1..16
    int line;        ///< line in the scene file
} wx_field;

typedef enum wx_emitter_kind {
    WX_EMITTER_POINT,
    WX_EMITTER_HEMISPHERE,
    WX_EMITTER_BOX, ///< docs/design.md section 8
} wx_emitter_kind;

typedef struct wx_emitter {
    wx_emitter_kind kind;
    char name[64];       ///< "" when not given
    float center[3];     ///< point and hemisphere emitters
    float radius;        ///< hemisphere radius (default 1); 0 for a point emitter
    float box_min[3];    ///< box emitter: start points uniform in [box_min, box_max]
    float box_max[3];
    float dir[3];        ///< box emitter: unit direction (default 0 -1 0)
    float spread;        ///< box emitter: cone half-angle in degrees, [0, 90) (default 0)
    double rate;         ///< particles per simulated second (default 1000)
    double start;        ///< seconds (default 0)
    double end;          ///< seconds (default: end of the simulation, steps*timeStep)
    float speed;         ///< m/s (default 1)
    float mass;          ///< default 1, > 0
    /// Load per particle of each substance (docs/design.md section 9): the
    /// `dirt` attribute is that of substance "dirt", <Load> children the
    /// others. Default 1 for "dirt" in a scene without <Substances>, else 0.
    float load[WX_MAX_SUBSTANCES];
    int max_collisions;  ///< default 100, >= 1
    int line;
} wx_emitter;

typedef struct wx_collider_def {
    float resilience; ///< R, default 0.5
    float friction;   ///< F, default 0.8
    float adherence;  ///< A, default 1
    float deposit;    ///< D, default 1
    float erosion;    ///< E, default 1
} wx_collider_def;

typedef enum wx_second_pass {
    WX_SECOND_PASS_MEAN, ///< weighted mean (docs/design.md section 5), the default
    WX_SECOND_PASS_SUM,  ///< the thesis' unnormalised weighted sum
} wx_second_pass;

/// The adaptive smoothing's defaults: the relative noise aimed at, and the
/// largest radius in output texels.
#define WX_DEFAULT_NOISE 0.04f
#define WX_DEFAULT_MAX_RADIUS_TEXELS 16.0f

/// An <Ortho> camera with its maps.
typedef struct wx_scene_camera {
    char name[64];     ///< cameraName: letters, digits, '_', '-', '.'
    bool is_output;    ///< out="true"
    wx_camera camera;  ///< matrices, and map size (from the maps or the View)
    bool has_view;     ///< given by <View> rather than (only) by matrices
    wx_view view;
    /// Map files resolved against the scene's folder (owned strings); NULL where
    /// the scene names none (a <View> camera whose maps `bake` will write).
    char *depth_path;
    char *normal_path;
    char *impact_path;
    char *dirt_path;
    /// The map paths point at maps this program wrote into the output folder
    /// (`bake`), not at files the scene names: later phases may replace them.
    bool maps_in_output;
    /// Output camera only (<OutputMap>).
    char output_file[256];   ///< base name in the output folder, default "mask.exr"
    int output_width;
    int output_height;
    /// Smoothing: with a radius (world units, 0 = none) today's second pass;
    /// without one (the default) the adaptive smoothing (docs/mask.md) aiming at
    /// relative noise `noise` with radii up to max_radius (world units).
    bool adaptive;
    float radius;
    float noise;             ///< default WX_DEFAULT_NOISE
    float max_radius;        ///< default WX_DEFAULT_MAX_RADIUS_TEXELS output texels
    wx_second_pass second_pass;
    bool normalize;          ///< scale the final mask to [0,1]
    int every;               ///< write BASE.NNNN.exr after every k-th iteration (0: none)
    /// <Ortho layers>: the crossings of each texel's view ray the camera
    /// records, nearest first (docs/design.md section 14); 1 to WX_MAX_LAYERS,
    /// default 1 (today's maps). Cameras whose maps the scene gives have 1.
    int layers;
    int line;
} wx_scene_camera;

typedef enum wx_color_use {
    WX_COLOR_NONE,   ///< ignore vertex colours (default)
    WX_COLOR_IMPACT, ///< impact R,G from the vertex colour's R,G
    WX_COLOR_DIRT,   ///< dirt density, deposit, erosion from R,G,B
} wx_color_use;

typedef enum wx_rule_kind {
    WX_RULE_TRANSFER, ///< t = rate * s_from; s_from -= t; s_to += t
    WX_RULE_DECAY,    ///< s -= rate * s
    WX_RULE_GROW,     ///< s += amount per square metre of surface
    /// Surface cellular automata (docs/design.md section 15): they read other
    /// surface points, so each runs over the whole surface before the next.
    WX_RULE_SEED,   ///< starts 1 per m^2 with probability 1 - exp(-density * area)
    WX_RULE_SPREAD, ///< takes 1 per m^2 within radius of a holder, with probability
    WX_RULE_CRACK,  ///< each crack tip takes its weakest neighbour within radius
    WX_RULE_PEEL,   ///< Spread from the points holding `from` (crack edges) or it
} wx_rule_kind;

/// One ageing rule (docs/design.md section 9), run on every surface texel
/// after each iteration.
typedef struct wx_rule {
    wx_rule_kind kind;
    int substance; ///< Transfer: from; Decay, Grow: the substance (index)
    int to;        ///< Transfer: to (index); Peel: from (index); else -1
    float rate;    ///< Transfer, Decay: in [0, 1]
    float amount;  ///< Grow: per square metre, >= 0
    int where;     ///< Seed, Spread: the substance that must lie there (index); -1: anywhere
    float min;     ///< Seed, Spread: the least amount of `where` per square metre
    float density; ///< Seed: seeds per square metre per iteration, >= 0
    float radius;  ///< Spread, Crack, Peel: world units along the surface, > 0
    float probability; ///< Spread, Peel: per point per iteration, in [0, 1]
    float strength;    ///< Crack: a point cracks when its flaw value is below it, [0, 1]
    int line;
} wx_rule;

/// Weathering properties of one material name ("*" matches every other).
typedef struct wx_surface {
    char material[128];
    float absorption; ///< impact R
    float bounce;     ///< impact G
    /// Per substance (index into wx_scene.substances): the initial amount per
    /// square metre and the exchange fractions. Substance "dirt"'s come from the
    /// dirt, deposit and erosion attributes, the others' from <Exchange>.
    float initial[WX_MAX_SUBSTANCES];
    float deposit[WX_MAX_SUBSTANCES];
    float erosion[WX_MAX_SUBSTANCES];
    wx_color_use colors; ///< vertexColors="none|impact|dirt"
    wx_rule *rules;      ///< this surface's own ageing rules, in document order (owned)
    int rule_count;
    int line;
} wx_surface;

/// The defaults of a <TextureMap> (docs/design.md section 11).
#define WX_DEFAULT_TEXTURE_RESOLUTION 1024
#define WX_DEFAULT_TEXTURE_PADDING 8

/// How a <TextureMap> reads UVs outside the unit square (`tiles`,
/// docs/texture.md "UVs outside [0,1]"); the order of the keywords.
typedef enum wx_uv_tiles {
    WX_TILES_REPEAT, ///< every UV tile folds onto the one texture, as a renderer's REPEAT reads it
    WX_TILES_UDIM,   ///< one texture per UDIM tile 1001 + u + 10 v the UVs cover
    WX_TILES_CLIP,   ///< the [0,1]^2 tile only; what lies outside is left out (CLIP)
} wx_uv_tiles;

/// UDIM tiles: 1001 + u + 10 v for u in 0..9, v in 0..99 (1001 to 2000, the
/// tiles Blender reads: its IMA_UDIM_MAX).
#define WX_UDIM_FIRST 1001
#define WX_UDIM_COLUMNS 10
#define WX_UDIM_ROWS 100
#define WX_UDIM_TILES (WX_UDIM_COLUMNS * WX_UDIM_ROWS)

/// A <TextureMap> of a <Mesh>: the mask's channels in the mesh's UV layout
/// (docs/design.md section 11, docs/texture.md).
typedef struct wx_texture_map {
    int mesh;            ///< index into wx_scene.meshes
    char file[256];      ///< base name in the output folder, ends in .exr
    int width, height;   ///< texels; `resolution` (default 1024), `width`/`height` override
    int padding;         ///< texels of island bleed, default 8 (0: none)
    int uv;              ///< the mesh's UV channel, default 0
    int every;           ///< write BASE.NNNN.exr after every k-th iteration (0: none)
    /// Smoothing as the mask's: a radius in world units (0: none) or, without
    /// one (the default), the adaptive smoothing aiming at `noise` with radii
    /// up to max_radius world units (0: WX_DEFAULT_MAX_RADIUS_TEXELS texels of
    /// the input camera the smoothing runs on; docs/texture.md).
    bool adaptive;
    float radius;
    float noise;
    float max_radius;
    wx_uv_tiles tiles;   ///< `tiles`, default repeat
    /// tiles="udim": the tiles (k = u + 10 v) where a texel centre lies inside
    /// a triangle of the UV layout, one bit each, known once the mesh is read
    /// (udim_known; pipeline/texture_phase.h wx_textures_find_tiles): the
    /// files BASE.(1001 + k).exr the run writes.
    bool udim_known;
    int udim_count;
    uint8_t udim[WX_UDIM_TILES / 8];
    int line;
} wx_texture_map;

/// Whether UDIM tile k (0 to WX_UDIM_TILES - 1, tile number 1001 + k) is one of
/// the texture's.
static inline bool wx_texture_has_tile(const wx_texture_map *t, int k)
{
    return (t->udim[k / 8] >> (k % 8)) & 1u;
}

/// The files (each with its previews and frames) texture t writes: one, or
/// with tiles="udim" one per tile its UVs cover (0 until known).
static inline int wx_texture_file_count(const wx_texture_map *t)
{
    return t->tiles == WX_TILES_UDIM ? t->udim_count : 1;
}

/// The UDIM tile index k (tile number 1001 + k) of texture t's file f, or -1
/// when the texture is not tiles="udim".
int wx_texture_file_tile(const wx_texture_map *t, int f);

/// The kinds of derived mask (docs/design.md section 12, docs/masks.md).
typedef enum wx_mask_kind {
    WX_MASK_ACCESSIBILITY, ///< cosine-weighted share of open directions within `distance`
    WX_MASK_EXPOSURE,      ///< direct light of a sun and two side suns, with real shadows
    WX_MASK_CURVATURE,     ///< mean curvature, 1/world unit (convex > 0)
    WX_MASK_HEIGHT,        ///< clamp((y - min) / (max - min), 0, 1)
    WX_MASK_COMBINE,       ///< clamp(scale * sum of terms, 0, 1)
    WX_MASK_NOISE,         ///< fractal Perlin noise of the world position, uniform by area
} wx_mask_kind;

typedef enum wx_term_kind {
    WX_TERM_MASK,      ///< a derived mask defined before the Combine
    WX_TERM_SUBSTANCE, ///< a substance, per square metre
    WX_TERM_CONSTANT,
    WX_TERM_AGE,       ///< constant * i / iterations in the frame after iteration i
} wx_term_kind;

/// One <Term> of a <Combine>: weight * S(x), S Riihiaho's sigmoid
/// (x - o) / (2 sqrt(1/s + (x - o)^2)) + 1/2 for steepness s > 0, else x.
typedef struct wx_term {
    wx_term_kind kind;
    int index;       ///< MASK: index into wx_scene.masks (< the Combine's); SUBSTANCE: substance
    float constant;  ///< CONSTANT: the value x; AGE: w of age="w"
    float weight;    ///< default 1
    float offset;    ///< o, default 0
    float steepness; ///< s >= 0, default 0 (S(x) = x)
    int line;
} wx_term;

/// Most <Term>s a <Combine> takes.
#define WX_MAX_TERMS 16
/// Most derived masks a scene takes (with the substances, at most
/// WX_IMAGE_MAX_CHANNELS - 1 channels in all: `seen` needs one).
#define WX_MAX_MASKS 24

/// Most octaves a <Noise> takes, and its highest frequency per world unit.
#define WX_NOISE_MAX_OCTAVES 16
#define WX_NOISE_MAX_FREQUENCY 1.0e6

/// One derived mask of <Masks> (docs/design.md section 12).
typedef struct wx_mask_def {
    wx_mask_kind kind;
    char name[WX_SUBSTANCE_NAME_MAX + 1]; ///< shares the substances' namespace; not Y, seen
    /// Accessibility: rays per point (1..4096, default 64), distance > 0 (world
    /// units, default 1).
    int rays;
    float distance;
    /// Exposure (degrees): elevation in [-90, 90] (default 45), azimuth from +X
    /// towards +Z (default 0), side_weight (default 0), side_elevation (a
    /// factor of elevation, default 1), side_spread (default 0).
    float elevation, azimuth, side_weight, side_elevation, side_spread;
    /// Curvature: radius in world units, 0 = 4 texels of the target.
    float radius;
    /// Height: the range of y; has_min/has_max false take the geometry's bounds.
    float min, max;
    bool has_min, has_max;
    /// Combine.
    float scale; ///< default 1
    wx_term terms[WX_MAX_TERMS];
    int term_count;
    /// Noise (docs/design.md section 15): frequency per world unit (> 0,
    /// default 1), octaves (1..16, default 4), gain (each octave's amplitude
    /// over the one before, [0, 1], default 0.5), its own seed (default 1).
    float frequency;
    int octaves;
    float gain;
    uint64_t noise_seed;
    int line;
} wx_mask_def;

/// <Tile>: the scene is one tile of a larger scene, as `weathering tiles`
/// writes it (docs/tiles.md). Its outputs hold only the surface points whose
/// x and z lie in [min, max) (an absent bound: unbounded), and its emitters fly
/// only the particles that start within `halo` world units of that region
/// (the others are drawn, so every particle keeps its index and random stream,
/// and dropped).
typedef struct wx_tile_def {
    bool present;
    double min[2]; ///< x, z; -INFINITY when not given
    double max[2]; ///< x, z; +INFINITY when not given
    double halo;   ///< >= 0, default 0
    int line;
} wx_tile_def;

/// Whether the tile owns the surface point at world x, z (always without a tile).
static inline bool wx_tile_owns(const wx_tile_def *t, double x, double z)
{
    return !t->present || (x >= t->min[0] && x < t->max[0] && z >= t->min[1] && z < t->max[1]);
}

/// Whether a particle starting at world x, z flies in the tile's run: within
/// `halo` of the tile (always without a tile).
static inline bool wx_tile_keeps(const wx_tile_def *t, double x, double z)
{
    return !t->present || (x >= t->min[0] - t->halo && x < t->max[0] + t->halo &&
                           z >= t->min[1] - t->halo && z < t->max[1] + t->halo);
}

typedef struct wx_mesh {
    char *path; ///< resolved against the scene's folder (owned)
    wx_surface *surfaces;
    int surface_count;
    int line;
} wx_mesh;

typedef struct wx_scene {
    char *path;             ///< the scene file as given (owned)
    char *dir;              ///< its folder, where relative paths resolve (owned)
    char name[256];         ///< file name without folder and extension

    float bbox_size;        ///< BoundingBox cube side, default 100
    float bbox_center[3];
    double time_step;       ///< seconds, default 0.01
    int64_t steps;          ///< default 1000
    uint64_t seed;          ///< default 1

    wx_field *fields;
    int field_count;
    wx_emitter *emitters;
    int emitter_count;
    wx_collider_def collider;

    wx_scene_camera *cameras; ///< input and output cameras in file order
    int camera_count;
    int input_count;
    int output_index;         ///< index into cameras, or -1

    wx_mesh *meshes;
    int mesh_count;

    /// Every <TextureMap>, in document order (owned).
    wx_texture_map *textures;
    int texture_count;

    /// <Masks>: the derived masks in document order (a Combine's terms name
    /// only masks before it).
    wx_mask_def masks[WX_MAX_MASKS];
    int mask_count;
    /// The geometry's bounds once imported (a run fills them for Height's
    /// default range); has_bounds false until then.
    double bounds_min[3], bounds_max[3];
    bool has_bounds;
    /// An area-weighted sample of the meshes' surfaces once imported (3
    /// doubles a point, world; wx_noise_sample_meshes): what a Noise mask's
    /// remap is built from. NULL without meshes or until a run fills it (the
    /// input cameras' texels are used then); the run owns it.
    const double *surface_sample;
    int64_t surface_sample_count;

    /// Substances (docs/design.md section 9): without <Substances> the one
    /// substance "dirt" (substances_declared false).
    int substance_count;
    char substances[WX_MAX_SUBSTANCES][WX_SUBSTANCE_NAME_MAX + 1];
    bool substances_declared;
    int dirt_substance;      ///< index of "dirt", or -1 when not declared
    int iterations;          ///< >= 1, default 1
    wx_rule *rules;          ///< global ageing rules (<Ageing>), document order (owned)
    int rule_count;
    /// <Tile>: present when the scene is one tile of a larger one.
    wx_tile_def tile;
} wx_scene;

/// Where the scene's particles live, the box where they escape: the bounding
/// box, within a tile's region and halo for a tile (x and z; docs/tiles.md).
static inline void wx_scene_particle_box(const wx_scene *scene, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; ++k) {
        lo[k] = scene->bbox_center[k] - 0.5f * scene->bbox_size;
        hi[k] = scene->bbox_center[k] + 0.5f * scene->bbox_size;
    }
    if (scene->tile.present) {
        for (int a = 0; a < 2; ++a) {
            int k = 2 * a; // x, then z
            double tlo = scene->tile.min[a] - scene->tile.halo;
            double thi = scene->tile.max[a] + scene->tile.halo;
            lo[k] = (float)((double)lo[k] > tlo ? (double)lo[k] : tlo);
            hi[k] = (float)((double)hi[k] < thi ? (double)hi[k] : thi);
        }
    }
}

/// True when a path is given (not NULL, not empty).
static inline bool wx_has_path(const char *path)
{
    return path != NULL && path[0] != '\0';
}

/// Replaces the owned string *slot by a copy of `path` (NULL: none). Returns
/// false when out of memory (*slot is then unchanged).
bool wx_scene_set_path(char **slot, const char *path);

/// Default collider parameters (docs/design.md section 3).
wx_collider_def wx_default_collider_def(void);

/// The mesh path as the scene file wrote it (relative to the scene's folder).
const char *wx_mesh_display_name(const wx_scene *scene, const wx_mesh *mesh);

/// Index of the substance called `name`, or -1.
int wx_scene_substance(const wx_scene *scene, const char *name);

/// True when the scene uses anything beyond version 1's one substance: declared
/// substances or ageing rules (global or per surface). Such a scene's mask has
/// a channel NAME.Y per substance (docs/design.md section 10).
bool wx_scene_has_ageing(const wx_scene *scene);

/// True when some surface has rules of its own: the bake then records which
/// surface each texel shows.
bool wx_scene_has_surface_rules(const wx_scene *scene);

/// True when some rule (global or per surface) grows a substance (Grow and the
/// surface automata: each needs the area each texel owns).
bool wx_scene_has_grow(const wx_scene *scene);

/// True when some rule (global or per surface) reads other surface points
/// (Seed, Spread, Crack, Peel): the ageing then runs rule by rule over the
/// whole surface.
bool wx_scene_has_surface_automata(const wx_scene *scene);

/// Whether an input camera holds more than one layer (docs/design.md section 14).
bool wx_scene_has_layers(const wx_scene *scene);

/// Total number of <Surface>s over all meshes; surface k of mesh m has the
/// global index wx_scene_surface_base(scene, m) + k.
int wx_scene_surface_count(const wx_scene *scene);
int wx_scene_surface_base(const wx_scene *scene, int mesh);

/// Every <Surface> by its global index: a malloc'd array of
/// wx_scene_surface_count(scene) pointers into the scene (the bake stores index
/// + 1 in a map's `surface` channel), or NULL when out of memory.
const wx_surface **wx_scene_surfaces_by_index(const wx_scene *scene);

/// Frees everything the scene owns; the struct is zeroed.
void wx_scene_free(wx_scene *scene);

/// Total simulated time, steps * time_step.
double wx_scene_duration(const wx_scene *scene);

#endif
