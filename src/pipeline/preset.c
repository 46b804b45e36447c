// preset.c: scenes generated for a mesh (preset.h, docs/presets.md).
#include "pipeline/preset.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/limits.h"
#include "core/matrix.h"
#include "gather/texture.h"
#include "io/mesh_import.h"
#include "io/scene_xml.h"
#include "model/geometry.h"
#include "model/mesh.h"
#include "pipeline/bake_phase.h"
#include "pipeline/pipeline.h"

const char *const wx_preset_names[] = { "rain", "dust", "soot", "moss", "rust", "old_paint" };
const int wx_preset_count = 6;

enum { PRESET_RAIN, PRESET_DUST, PRESET_SOOT, PRESET_MOSS, PRESET_RUST, PRESET_OLD_PAINT };

/// What a preset sets: the physics of its particles (relative to the mesh's
/// size s and the fall's duration) and its surfaces.
typedef struct preset {
    const char *what;     // one line for the scene's header
    double speed;         // launch speed, in mesh sizes per second
    double gravity;       // share of gravity (drag on dust and soot)
    double spread;        // degrees of the emitter's cone
    double wind;          // wind force, in shares of gravity
    double wind_dir[3];
    double turbulence;    // turbulence strength, in shares of gravity
    double particles;     // particles over the run (all iterations)
    int iterations;
    bool bottom;          // a camera below (particles reach undersides)
    double absorption, bounce, deposit, erosion;
    double resilience, friction;
} preset;

static const preset presets[] = {
    [PRESET_RAIN] = { "rain slanting in a steady wind: streaks below what sticks out, washed "
                      "tops, clean sheltered walls",
                      2.0, 1.0, 8.0, 0.3, { -1.0, 0.0, -0.4 }, 0.0, 400000, 1, false,
                      0.05, 0.15, 0.3, 0.4, 0.2, 0.9 },
    [PRESET_DUST] = { "dust settling from still air: tops and ledges gather it, undersides stay "
                      "clean",
                      0.3, 0.2, 20.0, 0.0, { 0.0, 0.0, 0.0 }, 0.1, 300000, 1, false,
                      0.3, 0.05, 0.8, 0.02, 0.1, 0.6 },
    [PRESET_SOOT] = { "soot drifting on a turbulent breeze: a sticky film on the windward side, "
                      "thinner on tops, some on undersides",
                      0.6, 0.02, 15.0, 0.03, { 1.0, 0.0, 0.3 }, 0.05, 300000, 1, true,
                      0.5, 0.05, 0.9, 0.01, 0.05, 0.8 },
    [PRESET_MOSS] = { "five rainy spells: the rain's water lingers, and the mask 'moss' grows "
                      "where it stays wet in shelter and shade",
                      2.0, 1.0, 8.0, 0.3, { -1.0, 0.0, -0.4 }, 0.0, 400000, 5, false,
                      0.3, 0.1, 0.5, 0.1, 0.2, 0.9 },
    [PRESET_RUST] = { "six rainy spells: the rain's water lingers, rust seeds where it stays and "
                      "blooms outwards along the wet surface, a frame per spell",
                      2.0, 1.0, 8.0, 0.3, { -1.0, 0.0, -0.4 }, 0.0, 400000, 6, false,
                      0.3, 0.1, 0.5, 0.1, 0.2, 0.9 },
    [PRESET_OLD_PAINT] = { "six rainy spells on old paint: it cracks, mostly where the rain "
                           "beats, and peels from the cracks where the water stays, a frame "
                           "per spell",
                           2.0, 1.0, 8.0, 0.3, { -1.0, 0.0, -0.4 }, 0.0, 400000, 6, false,
                           0.3, 0.1, 0.5, 0.1, 0.2, 0.9 },
};

// Whether a preset's rain carries water (a substance "water", an <Exchange>
// and its evaporation between spells).
static bool wet_preset(int pi)
{
    return pi == PRESET_MOSS || pi == PRESET_RUST || pi == PRESET_OLD_PAINT;
}

// Whether a preset grows its look with the surface automata (Seed, Spread,
// Crack, Peel: docs/design.md section 15), on inputs of half the resolution.
static bool automata_preset(int pi)
{
    return pi == PRESET_RUST || pi == PRESET_OLD_PAINT;
}

int wx_preset_find(const char *name)
{
    for (int p = 0; p < wx_preset_count; ++p) {
        if (strcmp(name, wx_preset_names[p]) == 0) {
            return p;
        }
    }
    return -1;
}

double wx_unit_metres(const char *name)
{
    static const struct {
        const char *name;
        double metres;
    } units[] = { { "m", 1.0 }, { "cm", 0.01 }, { "mm", 0.001 }, { "in", 0.0254 },
                  { "ft", 0.3048 } };
    for (size_t k = 0; k < sizeof units / sizeof units[0]; ++k) {
        if (strcmp(name, units[k].name) == 0) {
            return units[k].metres;
        }
    }
    return 0.0;
}

// ---------------------------------------------------------------------------
// The text.

typedef struct text {
    char *s;
    size_t len, cap;
    bool failed;
} text;

static void put(text *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static void put(text *t, const char *fmt, ...)
{
    for (int tries = 0; tries < 2 && !t->failed; ++tries) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(t->s != NULL ? t->s + t->len : NULL, t->s != NULL ? t->cap - t->len : 0,
                          fmt, ap);
        va_end(ap);
        if (n < 0) {
            t->failed = true;
            return;
        }
        if (t->s != NULL && t->len + (size_t)n < t->cap) {
            t->len += (size_t)n;
            return;
        }
        size_t cap = (t->cap + (size_t)n + 1) * 2;
        char *s = realloc(t->s, cap);
        if (s == NULL) {
            t->failed = true;
            return;
        }
        t->s = s;
        t->cap = cap;
    }
}

// A camera looking along -axis at the box centre c, from `distance` away, with
// a frame of `w` x `h` at `texel` world units a texel.
static void camera(text *t, const char *name, const double c[3], const double axis[3],
                   const double up[3], double distance, double w, double h, double texel, bool out,
                   int out_px, int layers, int every)
{
    int pw = out ? out_px : (int)fmin(16384.0, fmax(16.0, ceil(w / texel)));
    int ph = out ? out_px : (int)fmin(16384.0, fmax(16.0, ceil(h / texel)));
    char extra[32] = "";
    if (out) {
        snprintf(extra, sizeof extra, " out=\"true\"");
    } else if (layers > 1) {
        snprintf(extra, sizeof extra, " layers=\"%d\"", layers);
    }
    put(t,
        "      <Ortho cameraName=\"%s\"%s>\n"
        "        <View eye=\"%.9g %.9g %.9g\" target=\"%.9g %.9g %.9g\" up=\"%.6g %.6g %.6g\" "
        "width=\"%.9g\" height=\"%.9g\" resolution=\"%d %d\"/>\n",
        name, extra, c[0] + axis[0] * distance, c[1] + axis[1] * distance,
        c[2] + axis[2] * distance, c[0], c[1], c[2], up[0], up[1], up[2], w, h, pw, ph);
    if (out) {
        if (every > 0) {
            put(t, "        <OutputMap file=\"mask.exr\" every=\"%d\"/>\n", every);
        } else {
            put(t, "        <OutputMap file=\"mask.exr\"/>\n");
        }
    }
    put(t, "      </Ortho>\n");
}

// The layers init gives a camera looking along `axis`: the mesh's depth
// complexity along it (wx_mesh_depth_complexity over a LAYER_GRID lattice),
// at least 1 and at most INIT_LAYERS. A convex closed mesh needs 2 (its front
// and its back, so the space behind it is free); a house with a roof overhang
// and sills 4 or more. An odd count means a ray crosses a one-sided sheet (a
// sign, a pane): one layer more, so that the last layer stays empty where it
// does and the collider reads the sheet as a thin slab; with every layer full
// it reads "solid behind", and two cameras facing a sheet from its two sides
// then agree on its plane alone, which the rain passes through
// (docs/cameras.md, "Layers").
enum { INIT_LAYERS = 4, LAYER_GRID = 128 };

static int init_layers(const wx_mesh_data *mesh, const double axis[3])
{
    int k = wx_mesh_depth_complexity(mesh, axis, LAYER_GRID);
    if (k < 1) {
        return k < 0 ? INIT_LAYERS : 1;
    }
    k += k % 2;
    return k > INIT_LAYERS ? INIT_LAYERS : k;
}

// ---------------------------------------------------------------------------
// What every preset holds on any model (docs/presets.md).

// A particle dies at its 60th collision (the emitters' maxCollisions).
enum { MAX_COLLISIONS = 60 };
static const double DEG = 3.14159265358979323846 / 180.0;
// The output camera's elevation, degrees: between a side view and a plan.
static const double VIEW_LOW = 20.0, VIEW_HIGH = 60.0;
// Moss (the Combine 'moss'): the shelter's rays (most of the preset's cost:
// docs/presets.md), and the scale that takes a wet, sheltered surface in the
// shade to 1. A surface counts as sheltered when at least two of its rays
// meet a surface: one alone is as often a graze.
enum { MOSS_RAYS = 12 };
static const double MOSS_SCALE = 1.3;

// Rust and old paint (docs/presets.md): the surface automata after each spell
// (docs/design.md section 15), every length a multiple of the mesh's size s or
// of the input cameras' texel (itself one of s), every density per s^2, every
// amount of water a share of a spell's rain on open ground (`rain`, per square
// unit), so the look is the same at any size and unit.
static void ageing_automata(text *t, int pi, double s, double in_texel, double rain)
{
    const double s2 = s * s;
    if (pi == PRESET_RUST) {
        // Seeds where a fifth of a spell's open-ground rain stays, 30 per s^2
        // a spell; blooms growing up to s/100 (at least two texels) a spell
        // with probability 0.4, over surfaces that hold a twentieth.
        double seed_min = 0.2 * rain, spread_min = 0.05 * rain;
        double radius = fmax(0.01 * s, 2.0 * in_texel);
        put(t,
            "  <!-- After each spell: rust starts at random where a fifth of a spell's rain\n"
            "       on open ground (%.4g a square unit) or more stays, %.4g seeds a square\n"
            "       unit (30 over s x s) a spell; each bloom creeps %.4g (s/100, at least\n"
            "       two input texels) a spell over the surface that holds a twentieth\n"
            "       (%.4g), each point there taking it with probability 0.4, so the blooms'\n"
            "       edges fray; then half the water evaporates (docs/design.md section 15).\n"
            "       The frames mask.0001.exr ... show the blooms grow. -->\n"
            "  <Ageing>\n"
            "    <Seed substance=\"rust\" density=\"%.6g\" where=\"water\" min=\"%.6g\"/>\n"
            "    <Spread substance=\"rust\" radius=\"%.6g\" probability=\"0.4\" where=\"water\" "
            "min=\"%.6g\"/>\n"
            "    <Decay substance=\"water\" rate=\"0.5\"/>\n"
            "  </Ageing>\n",
            seed_min, 30.0 / s2, radius, spread_min, 30.0 / s2, seed_min, radius, spread_min);
        return;
    }
    // Old paint: cracks start mostly where the rain beats (a twentieth of a
    // spell's open-ground rain), a few anywhere; each grows three steps of
    // 1.5 input texels (neighbouring texels: a continuous line) a spell; the
    // paint peels from them where a fifth of a spell's rain stays.
    double beaten = 0.05 * rain, soaked = 0.2 * rain;
    double step = 1.5 * in_texel, flake = fmax(0.005 * s, 2.0 * in_texel);
    put(t,
        "  <!-- After each spell: cracks start where the rain beats (%.4g of water a square\n"
        "       unit, a twentieth of a spell's rain on open ground: the exposed surfaces),\n"
        "       %.4g a square unit (20 over s x s) a spell, and a fifth of that anywhere;\n"
        "       each crack then grows three steps of %.4g (1.5 input texels, so its\n"
        "       points touch) along the weakest paint, %.0f%% of which can crack. Where a\n"
        "       fifth of a spell's rain (%.4g) stays, the paint peels from the cracks'\n"
        "       edges and on from the flakes, %.4g a spell (s/200, at least two texels),\n"
        "       with probability 0.3 a point; then half the water evaporates\n"
        "       (docs/design.md section 15). The frames mask.0001.exr ... show it age. -->\n"
        "  <Ageing>\n"
        "    <Seed substance=\"crack\" density=\"%.6g\" where=\"water\" min=\"%.6g\"/>\n"
        "    <Seed substance=\"crack\" density=\"%.6g\"/>\n",
        beaten, 20.0 / s2, step, 60.0, soaked, flake, 20.0 / s2, beaten, 4.0 / s2);
    for (int k = 0; k < 3; ++k) {
        put(t, "    <Crack substance=\"crack\" radius=\"%.6g\" strength=\"0.6\"/>\n", step);
    }
    put(t,
        "    <Peel substance=\"peel\" from=\"crack\" radius=\"%.6g\" probability=\"0.3\" "
        "where=\"water\" min=\"%.6g\"/>\n"
        "    <Decay substance=\"water\" rate=\"0.5\"/>\n"
        "  </Ageing>\n",
        flake, soaked);
}

// The steepness of a Combine term's sigmoid (docs/masks.md) that goes from 0.1
// to 0.9 over its offset +- w: S(o + w) = 0.9 when w sqrt(s) = 4/3.
static double steepness_for(double w)
{
    return (4.0 / 3.0) * (4.0 / 3.0) / (w * w);
}

// Flight times: a particle without collisions and turbulence moves as
// p(t) = p0 + v0 t + a t^2 / 2 under the preset's gravity and wind (both
// constant accelerations, docs/physics.md); the run is sized from these times.
static void path_at(const double p0[3], const double v0[3], const double a[3], double t,
                    double p[3])
{
    for (int k = 0; k < 3; ++k) {
        p[k] = p0[k] + v0[k] * t + 0.5 * a[k] * t * t;
    }
}

static bool inside(const double p[3], const double lo[3], const double hi[3])
{
    return p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1] && p[2] >= lo[2] &&
           p[2] <= hi[2];
}

// Whether the segment a -> b meets the box [lo, hi] (slabs).
static bool segment_meets(const double a[3], const double b[3], const double lo[3],
                          const double hi[3])
{
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 3; ++k) {
        double d = b[k] - a[k];
        if (d == 0.0) {
            if (a[k] < lo[k] || a[k] > hi[k]) {
                return false;
            }
            continue;
        }
        double u = (lo[k] - a[k]) / d, w = (hi[k] - a[k]) / d;
        t0 = fmax(t0, fmin(u, w));
        t1 = fmin(t1, fmax(u, w));
    }
    return t0 <= t1;
}

// The first time within [0, t_max] at which the path meets the box [lo, hi]
// (`to_enter`: the mesh's box, which may be flat) or is outside it (the
// solver's); t_max when it never does. The path is followed in 4096 chords,
// the one where it happens halved 40 times.
static double first_time(const double p0[3], const double v0[3], const double a[3],
                         const double lo[3], const double hi[3], bool to_enter, double t_max)
{
    enum { SAMPLES = 4096 };
    double t0 = 0.0, p[3], q[3];
    path_at(p0, v0, a, 0.0, p);
    if (inside(p, lo, hi) == to_enter) {
        return 0.0;
    }
    for (int i = 1; i <= SAMPLES; ++i) {
        double t1 = t_max * i / SAMPLES;
        path_at(p0, v0, a, t0, p);
        path_at(p0, v0, a, t1, q);
        if (to_enter ? segment_meets(p, q, lo, hi) : !inside(q, lo, hi)) {
            for (int it = 0; it < 40; ++it) {
                double tm = 0.5 * (t0 + t1);
                path_at(p0, v0, a, tm, q);
                if (to_enter ? segment_meets(p, q, lo, hi) : !inside(q, lo, hi)) {
                    t1 = tm;
                } else {
                    t0 = tm;
                    path_at(p0, v0, a, t0, p);
                }
            }
            return t1;
        }
        t0 = t1;
    }
    return t_max;
}

// Unit vectors at `spread` degrees around the unit vector d (its cone's rim),
// with d itself first: five launch directions.
static void cone_rim(const double d[3], double spread_deg, double out[5][3])
{
    double e1[3], e2[3];
    wx_perpendicular_basis(d, e1, e2);
    double c = cos(spread_deg * DEG), sn = sin(spread_deg * DEG);
    const double *side[4] = { e1, e2, e1, e2 };
    for (int k = 0; k < 3; ++k) {
        out[0][k] = d[k];
    }
    for (int r = 0; r < 4; ++r) {
        double sign = r < 2 ? 1.0 : -1.0;
        for (int k = 0; k < 3; ++k) {
            out[r + 1][k] = c * d[k] + sign * sn * side[r][k];
        }
    }
}

void wx_mesh_name(const char *path, char *out, size_t cap)
{
    char raw[WX_PATH_MAX];
    const char *slash = strrchr(path, '/');
    snprintf(raw, sizeof raw, "%s", slash != NULL ? slash + 1 : path);
    size_t n = strlen(raw);
    if (n >= 9 && strcasecmp(raw + n - 9, ".mesh.xml") == 0) {
        raw[n - 9] = '\0'; // Ogre's double extension
    } else {
        char *dot = strrchr(raw, '.');
        if (dot != NULL && dot != raw) {
            *dot = '\0';
        }
    }
    wx_default_out_name(raw, out, cap);
}

// `in` as an XML attribute value (malloc'd; NULL when out of memory).
static char *escape_attr(const char *in)
{
    char *out = malloc(6 * strlen(in) + 1);
    size_t n = 0;
    for (; out != NULL && *in != '\0'; ++in) {
        const char *rep = *in == '&' ? "&amp;" : *in == '"' ? "&quot;" : *in == '<' ? "&lt;"
                                               : *in == '>' ? "&gt;" : NULL;
        if (rep != NULL) {
            memcpy(out + n, rep, strlen(rep));
            n += strlen(rep);
        } else {
            out[n++] = *in;
        }
    }
    if (out != NULL) {
        out[n] = '\0';
    }
    return out;
}

// Why `path` cannot be written into a scene file as it is, or NULL: XML holds
// UTF-8 text only, and normalises tabs and line breaks in attributes to spaces.
static const char *unwritable_path(const char *path)
{
    const unsigned char *s = (const unsigned char *)path;
    while (*s != '\0') {
        int extra = *s < 0x80 ? 0 : (*s & 0xe0) == 0xc0 ? 1 : (*s & 0xf0) == 0xe0 ? 2
                                 : (*s & 0xf8) == 0xf0 ? 3 : -1;
        if (*s < 0x20 || *s == 0x7f) {
            return "holds a control character";
        }
        if (extra < 0 || (extra == 1 && *s < 0xc2) || (extra == 3 && *s > 0xf4)) {
            return "is not UTF-8 text";
        }
        for (int k = 1; k <= extra; ++k) {
            if ((s[k] & 0xc0) != 0x80) {
                return "is not UTF-8 text";
            }
        }
        s += 1 + extra;
    }
    return NULL;
}

// The name in the scene's header comment: no "--" (which ends an XML comment).
static void comment_name(const char *base, char *out, size_t cap)
{
    snprintf(out, cap, "%s", base);
    for (char *p = out; *p != '\0'; ++p) {
        if (*p == '-' && p > out && p[-1] == '-') {
            *p = '_';
        }
    }
}

// Whether the UVs are a UDIM layout: some triangle lies wholly in a tile other
// than 1001 and covers a texel there (a layout in [0,1] whose borders a few UVs
// overshoot by a hair is not one: REPEAT reads it right), and at most 1% of
// the triangles reach outside the tiles 1001 to 2000 (slivers across u = 0 of
// a UDIM asset: a renderer finds no tile there either).
static bool udim_layout(const wx_uv_survey *s)
{
    bool beyond_first = false;
    for (int k = 1; k < WX_UDIM_TILES; ++k) {
        beyond_first = beyond_first || ((s->udim[k / 8] >> (k % 8)) & 1u);
    }
    int64_t usable = s->triangles - s->triangles_unusable;
    return s->triangles_in_other_tiles > 0 && beyond_first &&
           100 * s->triangles_outside_udim <= usable;
}

// The <TextureMap> of a mesh with UVs (docs/presets.md): tiles="udim" for a
// UDIM layout, the default REPEAT otherwise, none when the layout covers no
// texel (then a note here and on stderr).
static void texture_map(text *t, const wx_init_def *def, const wx_uv_survey *s,
                        const char *base, int R)
{
    const bool udim = udim_layout(s);
    if (!(udim ? s->udim_count > 0 : s->covers)) {
        char why[200], unusable[96] = "";
        if (s->triangles_unusable > 0) {
            snprintf(unusable, sizeof unusable, ", %lld a UV not finite or over %d tiles",
                     (long long)s->triangles_unusable, WX_UV_MAX_TILES_PER_TRIANGLE);
        }
        snprintf(why, sizeof why, "of its %lld triangles, %lld have no area in UV%s",
                 (long long)s->triangles, (long long)s->triangles_degenerate, unusable);
        wx_note(def->quiet,
                "%s: the mesh's UV layout covers no texel at %d x %d (%s): the scene has no "
                "<TextureMap>",
                def->mesh_path, R, R, why);
        put(t,
            "      <!-- The mesh has UVs, but its layout covers no texel at %d x %d:\n"
            "           %s. No <TextureMap>: give the mesh a UV\n"
            "           layout to add one (docs/texture.md). -->\n",
            R, R, why);
        return;
    }
    if (udim) {
        int first = -1, last = -1;
        for (int k = 0; k < WX_UDIM_TILES; ++k) {
            if ((s->udim[k / 8] >> (k % 8)) & 1u) {
                first = first < 0 ? k : first;
                last = k;
            }
        }
        put(t,
            "      <!-- The mesh's UVs lie in %d UDIM tiles (%d to %d): one texture file per tile,\n"
            "           %s_texture.%d.exr ...; Blender reads them through its <UDIM> token\n"
            "           (docs/texture.md). -->\n"
            "      <TextureMap file=\"%s_texture.exr\" resolution=\"%d\" tiles=\"udim\"/>\n",
            s->udim_count, WX_UDIM_FIRST + first, WX_UDIM_FIRST + last, base,
            WX_UDIM_FIRST + first, base, R);
        return;
    }
    if (s->triangles_outside_unit > 0) {
        put(t,
            "      <!-- The mesh has UVs: the weathering in its own layout too (docs/texture.md).\n"
            "           They reach from (%.4g, %.4g) to (%.4g, %.4g): outside [0,1] they wrap\n"
            "           onto the texture as a renderer's REPEAT reads them. -->\n",
            s->uv_min[0], s->uv_min[1], s->uv_max[0], s->uv_max[1]);
    } else {
        put(t, "      <!-- The mesh has UVs: the weathering in its own layout too (docs/texture.md). -->\n");
    }
    put(t, "      <TextureMap file=\"%s_texture.exr\" resolution=\"%d\"/>\n", base, R);
}

static wx_result generate(const wx_init_def *def, const preset *p, int pi,
                          const wx_mesh_data *mesh, bool uvs, char **out_text, wx_error *err);

wx_result wx_scene_generate(const wx_init_def *def, char **out_text, wx_error *err)
{
    *out_text = NULL;
    int pi = wx_preset_find(def->preset != NULL ? def->preset : "rain");
    if (pi < 0) {
        return wx_fail(err, WX_CAUSE_USAGE,
                       "unknown preset '%s' (presets: rain, dust, soot, moss, rust, old_paint)",
                       def->preset);
    }
    const preset *p = &presets[pi];
    const char *why = unwritable_path(def->mesh_ref);
    if (why != NULL) {
        return wx_fail(err, WX_CAUSE_BAD_MESH,
                       "%s: the mesh's path %s, which a scene file cannot hold; rename the mesh "
                       "file (or its folders)",
                       def->mesh_path, why);
    }
    // The mesh: its bounds, and whether it has UVs (channel 0) for a TextureMap.
    wx_mesh_data mesh;
    bool uvs = true;
    wx_result r = wx_mesh_import_uvs(def->mesh_path, 1u, &mesh, err);
    if (r != WX_OK && err->cause == WX_CAUSE_NO_UVS) {
        uvs = false;
        r = wx_mesh_import(def->mesh_path, &mesh, err);
    }
    if (r != WX_OK) {
        return r;
    }
    r = generate(def, p, pi, &mesh, uvs, out_text, err);
    wx_mesh_data_free(&mesh);
    return r;
}

// Whether a mesh of largest extent `size` around `c` fits the scene's single
// precision: cameras whose matrices the scene check takes (a frame between
// WX_INIT_MIN_SIZE and WX_INIT_MAX_SIZE across), and float positions that
// resolve a quarter of the cameras' texel at the farthest point of the
// solver's box (the largest coordinate of the centre plus three sizes). NULL
// when it fits, else why not.
static const char *precision_problem(const double c[3], double size, double texel, char *why,
                                     size_t cap)
{
    if (size < WX_INIT_MIN_SIZE || size > WX_INIT_MAX_SIZE) {
        snprintf(why, cap, "is %g across, %s than the %g the scene's single precision takes; "
                 "scale it (and give --units)", size, size < WX_INIT_MIN_SIZE ? "smaller"
                 : "larger", size < WX_INIT_MIN_SIZE ? WX_INIT_MIN_SIZE : WX_INIT_MAX_SIZE);
        return why;
    }
    double far = 0.0;
    for (int k = 0; k < 3; ++k) {
        far = fmax(far, fabs(c[k]));
    }
    // The spacing of floats at the farthest point: 2^-23 of it.
    if ((far + 3.0 * size) * 0x1p-23 > 0.25 * texel) {
        snprintf(why, cap, "is only %g across but has coordinates up to %g: floats there are "
                 "%g apart, more than a quarter of a camera texel (%g); move it to the origin",
                 size, far, (far + 3.0 * size) * 0x1p-23, texel);
        return why;
    }
    return NULL;
}

// The scene for an imported mesh (wx_scene_generate).
static wx_result generate(const wx_init_def *def, const preset *p, int pi,
                          const wx_mesh_data *mesh, bool uvs, char **out_text, wx_error *err)
{
    int64_t triangles = mesh->triangle_count;
    double lo[3], hi[3];
    memcpy(lo, mesh->bounds_min, sizeof lo);
    memcpy(hi, mesh->bounds_max, sizeof hi);
    if (triangles == 0) {
        return wx_fail(err, WX_CAUSE_BAD_MESH, "%s: the mesh has no triangles", def->mesh_path);
    }
    double ext[3], c[3], size = 0.0;
    for (int k = 0; k < 3; ++k) {
        ext[k] = hi[k] - lo[k];
        c[k] = 0.5 * (lo[k] + hi[k]);
        size = fmax(size, ext[k]);
    }
    if (!(size > 0.0) || !isfinite(size)) {
        return wx_fail(err, WX_CAUSE_BAD_MESH, "%s: the mesh has no extent", def->mesh_path);
    }
    const int R = def->resolution > 0 ? def->resolution : 1024;
    // How the TextureMap reads the UVs, or none when they cover no texel.
    wx_uv_survey survey;
    memset(&survey, 0, sizeof survey);
    if (uvs) {
        wx_result r = wx_uv_survey_build(mesh, 0, R, R, &survey, err);
        if (r != WX_OK) {
            return r;
        }
    }
    const double unit = def->unit_m > 0.0 ? def->unit_m : 1.0;
    const double margin = 0.1 * size;
    const double texel = (size + 2.0 * margin) / R;
    char why[320];
    if (precision_problem(c, size, texel, why, sizeof why) != NULL) {
        return wx_fail(err, WX_CAUSE_BAD_MESH, "%s: the mesh %s", def->mesh_path, why);
    }
    // The input cameras' texel: moss's at a quarter of the resolution, at
    // least 256 texels across (below); rust's and old paint's at half, at
    // least 256 across: their automata's points are these texels, and a
    // bloom's or a crack's edge is one of them wide.
    const double in_texel = pi == PRESET_MOSS && R > 256 ? texel * R / fmax(256.0, 0.25 * R)
                            : automata_preset(pi) && R > 256 ? texel * R / fmax(256.0, 0.5 * R)
                                                             : texel;

    // The fall: from H above the top at the preset's speed under its gravity;
    // the wind's drift over it widens the emitter upwind.
    const double g = 9.8 / unit * p->gravity, H = 0.75 * size, v = p->speed * size;
    // (-v + sqrt(v^2 + 2gH)) / g without the cancellation that makes it 0 when
    // v^2 dwarfs 2gH (a mesh 1e30 across).
    const double fall = 2.0 * H / (v + sqrt(v * v + 2.0 * g * H));
    double wind_len = sqrt(p->wind_dir[0] * p->wind_dir[0] + p->wind_dir[1] * p->wind_dir[1] +
                           p->wind_dir[2] * p->wind_dir[2]);
    double wind = p->wind * 9.8 / unit, drift[3] = { 0.0, 0.0, 0.0 };
    double accel[3] = { 0.0, -g, 0.0 }; // gravity and wind: the force on a unit mass
    for (int k = 0; k < 3 && wind_len > 0.0; ++k) {
        drift[k] = 0.5 * wind * fall * fall * p->wind_dir[k] / wind_len;
        accel[k] += wind * p->wind_dir[k] / wind_len;
    }
    double e_lo[3] = { lo[0] - margin, hi[1] + H, lo[2] - margin };
    double e_hi[3] = { hi[0] + margin, hi[1] + H, hi[2] + margin };
    for (int k = 0; k < 3; k += 2) {
        // The drops drift by drift[k]: start them that far upwind.
        e_lo[k] -= fmax(0.0, drift[k]);
        e_hi[k] -= fmin(0.0, drift[k]);
    }
    double edir[3] = { 0.0, -1.0, 0.0 };
    if (pi == PRESET_SOOT) {
        // Soot drifts in from the side: a wall of emitters upwind of the mesh,
        // blowing along the wind, over the mesh's height and depth.
        e_lo[0] = e_hi[0] = lo[0] - H;
        e_lo[1] = lo[1] - margin;
        e_hi[1] = hi[1] + margin;
        e_lo[2] = lo[2] - margin;
        e_hi[2] = hi[2] + margin;
        for (int k = 0; k < 3; ++k) {
            edir[k] = p->wind_dir[k] / wind_len;
        }
    }
    // The solver's box: s/4 around the mesh and s/10 around the emitter, its
    // floor s/20 below the mesh, the cube's slack above and evenly on the
    // sides. A particle that missed or ran off then leaves soon instead of
    // flying on; and none reaches the space under the mesh below the side
    // cameras' frames (s/10 below it), where the top camera alone would
    // answer and call every point under the mesh's outline a collision (the
    // point rule, docs/physics.md) with the top of the mesh.
    const double pad = 0.25 * size;
    double box_lo[3], box_hi[3], bc[3], box = 0.0;
    for (int k = 0; k < 3; ++k) {
        box_lo[k] = fmin(k == 1 ? lo[k] - 0.5 * margin : lo[k] - pad, e_lo[k] - margin);
        box_hi[k] = fmax(hi[k] + pad, e_hi[k] + margin);
        box = fmax(box, box_hi[k] - box_lo[k]);
    }
    for (int k = 0; k < 3; ++k) {
        bc[k] = k == 1 ? box_lo[1] + 0.5 * box : 0.5 * (box_lo[k] + box_hi[k]);
        box_lo[k] = bc[k] - 0.5 * box;
        box_hi[k] = bc[k] + 0.5 * box;
    }
    // The approach: the emitter's central path into the mesh's bounding box;
    // 50 steps for it, emission over two approaches.
    const double t_max = 100.0 * fall;
    double ec[3], v0[3];
    for (int k = 0; k < 3; ++k) {
        ec[k] = 0.5 * (e_lo[k] + e_hi[k]);
        v0[k] = v * edir[k];
    }
    double approach = first_time(ec, v0, accel, lo, hi, true, t_max);
    if (!(approach > 0.0) || approach >= t_max) {
        approach = fall; // a path that grazes the box: the fall's time
    }
    const double dt = approach / 50.0, emit = 2.0 * approach;
    // What the last particles emitted need: a miss flies out of the box; a hit
    // reaches the mesh, collides at most MAX_COLLISIONS times (a sliding
    // particle collides every step, one that hops at least every other step)
    // and falls from rest out of the box. From
    // 3 x 3 x 3 points of the emitter along its direction and its cone's rim,
    // from every corner of the mesh's box; a quarter more for turbulence and
    // bounces.
    double dirs[5][3], miss = 0.0, reach = 0.0, from_rest = 0.0;
    cone_rim(edir, p->spread, dirs);
    static const double zero[3] = { 0.0, 0.0, 0.0 };
    for (int n = 0; n < 27; ++n) {
        double ep[3];
        for (int k = 0, m = n; k < 3; ++k, m /= 3) {
            ep[k] = e_lo[k] + 0.5 * (m % 3) * (e_hi[k] - e_lo[k]);
        }
        for (int dn = 0; dn < 5; ++dn) {
            double vd[3] = { v * dirs[dn][0], v * dirs[dn][1], v * dirs[dn][2] };
            miss = fmax(miss, first_time(ep, vd, accel, box_lo, box_hi, false, t_max));
            double in = first_time(ep, vd, accel, lo, hi, true, t_max);
            if (in < t_max) {
                reach = fmax(reach, in);
            }
        }
    }
    for (int corner = 0; corner < 8; ++corner) {
        double mp[3];
        for (int k = 0; k < 3; ++k) {
            mp[k] = (corner >> k & 1) ? hi[k] : lo[k];
        }
        from_rest = fmax(from_rest, first_time(mp, zero, accel, box_lo, box_hi, false, t_max));
    }
    const double after = 1.25 * fmax(miss, reach + 2 * MAX_COLLISIONS * dt + from_rest);
    const int steps = (int)ceil((emit + after) / dt);
    double rate = p->particles / p->iterations / emit;

    char base[256], header_name[256], preset_line[512];
    char *mesh_attr = escape_attr(def->mesh_ref);
    if (mesh_attr == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (scene text)");
    }
    wx_mesh_name(def->mesh_path, base, sizeof base);
    comment_name(base, header_name, sizeof header_name);
    snprintf(preset_line, sizeof preset_line, "%s", p->what);

    char iterations[48] = "";
    if (p->iterations > 1) {
        snprintf(iterations, sizeof iterations, " iterations=\"%d\"", p->iterations);
    }
    text t = { 0 };
    put(&t, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    put(&t,
        WX_GENERATED_SCENE_MARK "%s, preset %s (docs/presets.md): %s.\n"
        "     The mesh's bounding box is %.6g x %.6g x %.6g (largest extent s = %.6g) around\n"
        "     (%.9g, %.9g, %.9g); every size below is a multiple of s, so a model in\n"
        "     centimetres weathers as one in metres; gravity is 9.8 m/s^2 in the mesh's unit\n"
        "     (%.6g m). Edit freely: `weathering info` on this file checks it. -->\n",
        header_name, wx_preset_names[pi], preset_line, ext[0], ext[1], ext[2], size, c[0], c[1],
        c[2], unit);
    if (def->scene_name != NULL) {
        put(&t, "<Weathering name=\"%s\">\n", def->scene_name);
    } else {
        put(&t, "<Weathering>\n");
    }
    if (pi == PRESET_MOSS) {
        put(&t,
            "  <!-- The rain carries water; the mask 'moss' below says where it lingers in\n"
            "       shelter and shade. -->\n"
            "  <Substances>\n    <Substance name=\"water\"/>\n  </Substances>\n");
    } else if (pi == PRESET_RUST) {
        put(&t, "  <!-- The rain carries water; rust grows where it lingers (<Ageing> below). -->\n"
                "  <Substances>\n    <Substance name=\"water\"/>\n    <Substance name=\"rust\"/>\n"
                "  </Substances>\n");
    } else if (pi == PRESET_OLD_PAINT) {
        put(&t, "  <!-- The rain carries water; the paint's cracks and its peeled flakes are\n"
                "       substances of their own, so the mask has crack.Y and peel.Y (<Ageing>\n"
                "       below). -->\n"
                "  <Substances>\n    <Substance name=\"water\"/>\n    <Substance name=\"crack\"/>\n"
                "    <Substance name=\"peel\"/>\n  </Substances>\n");
    }
    put(&t,
        "  <Solver>\n"
        "    <!-- A cube s/4 around the mesh and s/10 around the emitter, its floor s/20 below\n"
        "         the mesh (above the side cameras' frames: below them only the top camera\n"
        "         would see, and take everything under the mesh for its top): particles\n"
        "         leaving it are gone, so those that missed leave soon. -->\n"
        "    <BoundingBox size=\"%.6g\" centerX=\"%.9g\" centerY=\"%.9g\" centerZ=\"%.9g\"/>\n"
        "    <!-- The particles reach the mesh's box %.3g s after leaving the emitter: 50 steps\n"
        "         for that. They are emitted over twice that, then the run goes on %.3g s for\n"
        "         the last ones to land or leave: 1.25 x the longer of a miss's flight out of\n"
        "         the box (%.3g s) and a hit's approach (%.3g s), %d collisions (a step for\n"
        "         a slide, two for a hop) and fall from rest out of the box (%.3g s). -->\n"
        "    <Simulation timeStep=\"%.6g\" steps=\"%d\" seed=\"1\"%s/>\n"
        "  </Solver>\n",
        box, bc[0], bc[1], bc[2], approach, after, miss, reach, MAX_COLLISIONS, from_rest, dt,
        steps, iterations);
    put(&t, "  <ForceFields>\n");
    put(&t, "    <!-- Gravity%s, in the mesh's unit per second squared. -->\n"
            "    <Gravity acceleration=\"%.6g\"/>\n",
        p->gravity < 1.0 ? " slowed by the air's drag on fine particles" : "", g);
    if (p->wind > 0.0) {
        put(&t,
            "    <!-- A steady wind: over a fall it carries a particle (%.3g, %.3g) across;\n"
            "         the emitter starts that far upwind. -->\n"
            "    <Wind strength=\"%.6g\" dirX=\"%.6g\" dirY=\"%.6g\" dirZ=\"%.6g\"/>\n",
            drift[0], drift[2], wind, p->wind_dir[0], p->wind_dir[1], p->wind_dir[2]);
    }
    if (p->turbulence > 0.0) {
        put(&t,
            "    <!-- Eddies about a fifth of the mesh across. -->\n"
            "    <Turbulence strength=\"%.6g\" frequency=\"%.6g\" octaves=\"3\"/>\n",
            p->turbulence * 9.8 / unit, 5.0 / size);
    }
    put(&t, "  </ForceFields>\n");
    put(&t,
        "  <Emitters>\n"
        "    <!-- A rectangle over the footprint (plus a margin of s/10), %.3g s above the top\n"
        "         (for soot: upwind of the mesh, blowing along the wind), %.0f particles over\n"
        "         the run. -->\n"
        "    <BoxEmitter name=\"%s\" minX=\"%.9g\" minY=\"%.9g\" minZ=\"%.9g\" maxX=\"%.9g\" "
        "maxY=\"%.9g\" maxZ=\"%.9g\"\n"
        "                dirX=\"%.6g\" dirY=\"%.6g\" dirZ=\"%.6g\" spread=\"%.6g\" rate=\"%.6g\" "
        "start=\"0\" end=\"%.6g\"\n"
        "                speed=\"%.6g\" maxCollisions=\"%d\"%s>\n",
        0.75, p->particles, wx_preset_names[pi], e_lo[0], e_lo[1], e_lo[2], e_hi[0], e_hi[1],
        e_hi[2], edir[0], edir[1], edir[2], p->spread, rate, emit, v, MAX_COLLISIONS,
        wet_preset(pi) ? "" : " dirt=\"1\"");
    if (wet_preset(pi)) {
        put(&t, "      <Load substance=\"water\" amount=\"1\"/>\n");
    }
    put(&t, "    </BoxEmitter>\n  </Emitters>\n");
    put(&t,
        "  <Collider resilience=\"%.6g\" friction=\"%.6g\" adherence=\"1\" deposit=\"1\" "
        "erosion=\"1\">\n"
        "    <ProjectedMaps>\n"
        "      <!-- The mesh from four sides and above%s, frames s/10 wider than it, %.4g a\n"
        "           texel (a resolution of %d across the largest). -->\n",
        p->resilience, p->friction, p->bottom ? " and below" : "", in_texel,
        (int)ceil((size + 2.0 * margin) / in_texel - 1e-9));
    if (in_texel > texel && automata_preset(pi)) {
        put(&t,
            "      <!-- Half the output's and the texture's resolution (at least 256 across):\n"
            "           the %s rules' points are these texels, a quarter as many as at the\n"
            "           full resolution, so each spell's rules cost a quarter. -->\n",
            pi == PRESET_RUST ? "rust's" : "paint's");
    } else if (in_texel > texel) {
        put(&t,
            "      <!-- A quarter of the output's and the texture's resolution (at least 256\n"
            "           across): moss is a soft mask, its water smoothed over many texels and\n"
            "           its shelter looking s/7 around (30 texels and more); its shelter's\n"
            "           rays, marched through these maps, cost half as much as through maps\n"
            "           of the full resolution. -->\n");
    }
    double d = 2.0 * (size + 2.0 * margin);
    static const double Y[3] = { 0, 1, 0 }, NZ[3] = { 0, 0, -1 }, PZ[3] = { 0, 0, 1 };
    const double fx = ext[0] + 2 * margin, fy = ext[1] + 2 * margin, fz = ext[2] + 2 * margin;
    // Layers (docs/cameras.md, "Layers"): as many as the rays along each
    // axis cross surfaces, at most INIT_LAYERS.
    static const double X[3] = { 1, 0, 0 }, Z[3] = { 0, 0, 1 };
    const int lz = init_layers(mesh, Z), lx = init_layers(mesh, X), ly = init_layers(mesh, Y);
    put(&t,
        "      <!-- Layers: the surfaces a ray along the camera's axis crosses, at most %d\n"
        "           (the mesh's depth complexity along z, x, y: %d, %d, %d). -->\n",
        INIT_LAYERS, lz, lx, ly);
    camera(&t, "front", c, (const double[3]){ 0, 0, 1 }, Y, d, fx, fy, in_texel, false, 0, lz, 0);
    camera(&t, "back", c, (const double[3]){ 0, 0, -1 }, Y, d, fx, fy, in_texel, false, 0, lz, 0);
    camera(&t, "left", c, (const double[3]){ -1, 0, 0 }, Y, d, fz, fy, in_texel, false, 0, lx, 0);
    camera(&t, "right", c, (const double[3]){ 1, 0, 0 }, Y, d, fz, fy, in_texel, false, 0, lx, 0);
    camera(&t, "top", c, Y, NZ, d, fx, fz, in_texel, false, 0, ly, 0);
    if (p->bottom) {
        camera(&t, "bottom", c, (const double[3]){ 0, -1, 0 }, PZ, d, fx, fz, in_texel, false, 0,
               ly, 0);
    }
    // The output camera looks at the side the particles come at: against their
    // velocity where they reach the mesh (the wind's side; the front right
    // when they come straight down), from between VIEW_LOW and VIEW_HIGH
    // degrees above the horizon, a three-quarter view; its frame holds the
    // whole box whichever way it turns.
    double q[3], arrive[3];
    for (int k = 0; k < 3; ++k) {
        arrive[k] = v0[k] + accel[k] * approach;
    }
    double hx = -arrive[0], hz = -arrive[2], h = sqrt(hx * hx + hz * hz);
    double elevation = atan2(-arrive[1], h) / DEG;
    if (!(h > 1e-3 * fabs(arrive[1]))) {
        hx = 1.0; // straight down: the front right
        hz = 1.2;
        h = sqrt(hx * hx + hz * hz);
    }
    elevation = fmin(VIEW_HIGH, fmax(VIEW_LOW, elevation));
    q[0] = cos(elevation * DEG) * hx / h;
    q[1] = sin(elevation * DEG);
    q[2] = cos(elevation * DEG) * hz / h;
    double diag = sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]) + 2.0 * margin;
    put(&t,
        "      <!-- The output camera: a three-quarter view of the side the particles come at,\n"
        "           from azimuth %.0f degrees (from +X towards +Z), %.0f degrees up. -->\n",
        atan2(hz, hx) / DEG, elevation);
    camera(&t, "shot", c, q, Y, d, diag, diag, texel, true, R, 1, automata_preset(pi) ? 1 : 0);
    put(&t, "    </ProjectedMaps>\n  </Collider>\n");
    if (pi == PRESET_MOSS) {
        put(&t,
            "  <!-- Between spells half the water evaporates: what is left is the recent\n"
            "       rain's, the older spells' halved again each time. -->\n"
            "  <Ageing>\n    <Decay substance=\"water\" rate=\"0.5\"/>\n  </Ageing>\n");
    } else if (automata_preset(pi)) {
        ageing_automata(&t, pi, size, in_texel,
                        rate * emit / ((e_hi[0] - e_lo[0]) * (e_hi[2] - e_lo[2])));
    }
    put(&t,
        "  <Geometry>\n"
        "    <Mesh file=\"%s\">\n"
        "      <!-- Every material alike: edit or add <Surface material=\"NAME\"> per material. -->\n"
        "      <Surface material=\"*\" absorption=\"%.6g\" bounce=\"%.6g\"",
        mesh_attr, p->absorption, p->bounce);
    if (wet_preset(pi)) {
        put(&t, ">\n        <Exchange substance=\"water\" deposit=\"%.6g\" erosion=\"%.6g\"/>\n"
                "      </Surface>\n",
            p->deposit, p->erosion);
    } else {
        put(&t, " deposit=\"%.6g\" erosion=\"%.6g\"/>\n", p->deposit, p->erosion);
    }
    if (uvs) {
        texture_map(&t, def, &survey, base, R);
    }
    put(&t, "    </Mesh>\n  </Geometry>\n");
    if (pi == PRESET_MOSS) {
        // A tenth of a spell's rain per square unit of open ground; the sun
        // from downwind.
        double wet = 0.1 * rate * emit / ((e_hi[0] - e_lo[0]) * (e_hi[2] - e_lo[2]));
        double sun_azimuth = fmod(atan2(p->wind_dir[2], p->wind_dir[0]) / DEG + 360.0, 360.0);
        put(&t,
            "  <!-- Moss grows where the surface stays wet AND is sheltered, less in the sun\n"
            "       (docs/masks.md, docs/presets.md): 'moss' = %.3g x (S(water) - S(shelter)\n"
            "       - 0.5 sun - 0.1), clamped to [0, 1]. S(water) is past 0.9 from a tenth of a\n"
            "       spell's rain on open ground (%.4g a square unit) up; S(shelter) is 0.9 and\n"
            "       more from shelter %.3g up (one ray of the shelter's blocked: a graze as\n"
            "       often as not) and 0.1 from %.3g down (two), so open ground has no moss\n"
            "       however wet, and dry ground none however sheltered. The sun shines from\n"
            "       downwind, so the wet windward side is the shady one. -->\n"
            "  <Masks>\n"
            "    <Accessibility name=\"shelter\" rays=\"%d\" distance=\"%.6g\"/>\n"
            "    <Exposure name=\"sun\" elevation=\"50\" azimuth=\"%.4g\"/>\n"
            "    <Combine name=\"moss\" scale=\"%.3g\">\n"
            "      <Term substance=\"water\" offset=\"%.6g\" steepness=\"%.6g\"/>\n"
            "      <Term mask=\"shelter\" weight=\"-1\" offset=\"%.3g\" steepness=\"%.4g\"/>\n"
            "      <Term mask=\"sun\" weight=\"-0.5\"/>\n"
            "      <Term constant=\"-0.1\"/>\n"
            "    </Combine>\n"
            "  </Masks>\n",
            MOSS_SCALE, wet, 1.0 - 1.0 / MOSS_RAYS, 1.0 - 2.0 / MOSS_RAYS, MOSS_RAYS, 0.15 * size,
            sun_azimuth, MOSS_SCALE, 0.5 * wet, steepness_for(0.5 * wet), 1.0 - 1.5 / MOSS_RAYS,
            steepness_for(0.5 / MOSS_RAYS));
    }
    put(&t, "</Weathering>\n");
    free(mesh_attr);
    if (t.failed) {
        free(t.s);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "out of memory (scene text)");
    }
    // The scene as a run will read it, before anyone writes it: a mesh the
    // checks above let through but the scene check refuses is still refused
    // here, naming the mesh, and nothing is written.
    const char *scene_path = def->scene_path != NULL ? def->scene_path : "scene.xml";
    wx_scene scene;
    wx_error load_err;
    if (wx_scene_load_text(scene_path, t.s, t.len, &scene, &load_err) != WX_OK) {
        free(t.s);
        if (load_err.cause == WX_CAUSE_OUT_OF_MEMORY) {
            *err = load_err;
            return WX_FAIL;
        }
        return wx_fail(err, WX_CAUSE_BAD_MESH,
                       "%s: no valid scene can be made for this mesh (bounds (%g, %g, %g) to "
                       "(%g, %g, %g)): %s",
                       def->mesh_path, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
                       load_err.message);
    }
    // A mesh the generated cameras see edge-on (no thickness along an axis)
    // gets its scene, with the warning that its run will be all zero.
    wx_geometry_mesh one = { .data = *mesh };
    wx_geometry geometry = { .count = 1, .meshes = &one };
    wx_geometry_warn_blind(&scene, &geometry, def->mesh_path, def->quiet);
    wx_scene_free(&scene);
    *out_text = t.s;
    return WX_OK;
}
