// preset.c: scenes generated for a mesh (preset.h, docs/presets.md).
#include "pipeline/preset.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/limits.h"
#include "gather/texture.h"
#include "io/mesh_import.h"
#include "io/scene_xml.h"
#include "model/geometry.h"
#include "model/mesh.h"
#include "pipeline/bake_phase.h"
#include "pipeline/pipeline.h"

const char *const wx_preset_names[] = { "rain", "dust", "soot", "moss" };
const int wx_preset_count = 4;

enum { PRESET_RAIN, PRESET_DUST, PRESET_SOOT, PRESET_MOSS };

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
    [PRESET_MOSS] = { "five rainy spells: the rain's water lingers, moss grows from it where it "
                      "stays wet, and a 'mossy' mask adds shelter and shade",
                      2.0, 1.0, 8.0, 0.3, { -1.0, 0.0, -0.4 }, 0.0, 400000, 5, false,
                      0.3, 0.1, 0.5, 0.1, 0.2, 0.9 },
};

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
                   const double up[3], double distance, double w, double h, double texel,
                   bool out, int out_px)
{
    int pw = out ? out_px : (int)fmin(16384.0, fmax(16.0, ceil(w / texel)));
    int ph = out ? out_px : (int)fmin(16384.0, fmax(16.0, ceil(h / texel)));
    put(t,
        "      <Ortho cameraName=\"%s\"%s>\n"
        "        <View eye=\"%.9g %.9g %.9g\" target=\"%.9g %.9g %.9g\" up=\"%.6g %.6g %.6g\" "
        "width=\"%.9g\" height=\"%.9g\" resolution=\"%d %d\"/>\n",
        name, out ? " out=\"true\"" : "", c[0] + axis[0] * distance, c[1] + axis[1] * distance,
        c[2] + axis[2] * distance, c[0], c[1], c[2], up[0], up[1], up[2], w, h, pw, ph);
    if (out) {
        put(t, "        <OutputMap file=\"mask.exr\"/>\n");
    }
    put(t, "      </Ortho>\n");
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
        return wx_fail(err, WX_CAUSE_USAGE, "unknown preset '%s' (presets: rain, dust, soot, moss)",
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

    // The fall: from H above the top at the preset's speed under its gravity.
    const double g = 9.8 / unit * p->gravity, H = 0.75 * size, v = p->speed * size;
    // (-v + sqrt(v^2 + 2gH)) / g without the cancellation that makes it 0 when
    // v^2 dwarfs 2gH (a mesh 1e30 across).
    const double fall = 2.0 * H / (v + sqrt(v * v + 2.0 * g * H));
    const double dt = fall / 50.0, emit = 2.0 * fall;
    const int steps = (int)ceil((emit + 3.0 * fall) / dt);
    // The wind's drift over the fall widens the emitter upwind.
    double wind_len = sqrt(p->wind_dir[0] * p->wind_dir[0] + p->wind_dir[1] * p->wind_dir[1] +
                           p->wind_dir[2] * p->wind_dir[2]);
    double wind = p->wind * 9.8 / unit, drift[3] = { 0.0, 0.0, 0.0 };
    for (int k = 0; k < 3 && wind_len > 0.0; ++k) {
        drift[k] = 0.5 * wind * fall * fall * p->wind_dir[k] / wind_len;
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
    double box = 2.0 * fmax(size, fmax(e_hi[0] - e_lo[0], e_hi[2] - e_lo[2])) + 2.0 * H;
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
            "  <!-- The rain carries water; moss grows from the water that stays. -->\n"
            "  <Substances>\n    <Substance name=\"water\"/>\n    <Substance name=\"moss\"/>\n"
            "  </Substances>\n");
    }
    put(&t,
        "  <Solver>\n"
        "    <!-- A cube around the mesh and the emitter: particles leaving it are gone. -->\n"
        "    <BoundingBox size=\"%.6g\" centerX=\"%.9g\" centerY=\"%.9g\" centerZ=\"%.9g\"/>\n"
        "    <!-- A fall of 0.75 s from the emitter to the top takes %.3g s: 50 steps a fall;\n"
        "         particles are emitted over two falls and fly three more. -->\n"
        "    <Simulation timeStep=\"%.6g\" steps=\"%d\" seed=\"1\"%s/>\n"
        "  </Solver>\n",
        box, c[0], c[1] + 0.5 * H, c[2], fall, dt, steps, iterations);
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
        "                speed=\"%.6g\" maxCollisions=\"60\"%s>\n",
        0.75, p->particles, wx_preset_names[pi], e_lo[0], e_lo[1], e_lo[2], e_hi[0], e_hi[1],
        e_hi[2], edir[0], edir[1], edir[2], p->spread, rate, emit, v,
        pi == PRESET_MOSS ? "" : " dirt=\"1\"");
    if (pi == PRESET_MOSS) {
        put(&t, "      <Load substance=\"water\" amount=\"1\"/>\n");
    }
    put(&t, "    </BoxEmitter>\n  </Emitters>\n");
    put(&t,
        "  <Collider resilience=\"%.6g\" friction=\"%.6g\" adherence=\"1\" deposit=\"1\" "
        "erosion=\"1\">\n"
        "    <ProjectedMaps>\n"
        "      <!-- The mesh from four sides and above%s, frames s/10 wider than it, %.4g a\n"
        "           texel (a resolution of %d across the largest). -->\n",
        p->resilience, p->friction, p->bottom ? " and below" : "", texel, R);
    double d = 2.0 * (size + 2.0 * margin);
    static const double Y[3] = { 0, 1, 0 }, NZ[3] = { 0, 0, -1 }, PZ[3] = { 0, 0, 1 };
    const double fx = ext[0] + 2 * margin, fy = ext[1] + 2 * margin, fz = ext[2] + 2 * margin;
    camera(&t, "front", c, (const double[3]){ 0, 0, 1 }, Y, d, fx, fy, texel, false, 0);
    camera(&t, "back", c, (const double[3]){ 0, 0, -1 }, Y, d, fx, fy, texel, false, 0);
    camera(&t, "left", c, (const double[3]){ -1, 0, 0 }, Y, d, fz, fy, texel, false, 0);
    camera(&t, "right", c, (const double[3]){ 1, 0, 0 }, Y, d, fz, fy, texel, false, 0);
    camera(&t, "top", c, Y, NZ, d, fx, fz, texel, false, 0);
    if (p->bottom) {
        camera(&t, "bottom", c, (const double[3]){ 0, -1, 0 }, PZ, d, fx, fz, texel, false, 0);
    }
    // A three-quarter view from the front right, above; its frame holds the
    // whole box whichever way it turns.
    double q[3] = { 1.0, 0.8, 1.2 }, ql = sqrt(1.0 + 0.64 + 1.44);
    for (int k = 0; k < 3; ++k) {
        q[k] /= ql;
    }
    double diag = sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]) + 2.0 * margin;
    put(&t, "      <!-- The output camera: a three-quarter view from the front right. -->\n");
    camera(&t, "shot", c, q, Y, d, diag, diag, texel, true, R);
    put(&t, "    </ProjectedMaps>\n  </Collider>\n");
    if (pi == PRESET_MOSS) {
        put(&t,
            "  <!-- Between spells half the water evaporates and a tenth of what is left\n"
            "       becomes moss. -->\n"
            "  <Ageing>\n    <Transfer from=\"water\" to=\"moss\" rate=\"0.1\"/>\n"
            "    <Decay substance=\"water\" rate=\"0.5\"/>\n  </Ageing>\n");
    }
    put(&t,
        "  <Geometry>\n"
        "    <Mesh file=\"%s\">\n"
        "      <!-- Every material alike: edit or add <Surface material=\"NAME\"> per material. -->\n"
        "      <Surface material=\"*\" absorption=\"%.6g\" bounce=\"%.6g\"",
        mesh_attr, p->absorption, p->bounce);
    if (pi == PRESET_MOSS) {
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
        put(&t,
            "  <!-- Where moss would look right: wet, sheltered, shaded (docs/masks.md). -->\n"
            "  <Masks>\n"
            "    <Accessibility name=\"shelter\" rays=\"32\" distance=\"%.6g\"/>\n"
            "    <Exposure name=\"sun\" elevation=\"50\" azimuth=\"200\" sideWeight=\"0.4\" "
            "sideElevation=\"0.7\" sideSpread=\"60\"/>\n"
            "    <Combine name=\"mossy\">\n"
            "      <Term substance=\"water\" weight=\"0.7\" offset=\"%.6g\" steepness=\"%.6g\"/>\n"
            "      <Term mask=\"shelter\" weight=\"-0.6\" offset=\"0.75\" steepness=\"40\"/>\n"
            "      <Term mask=\"sun\" weight=\"-0.5\"/>\n"
            "      <Term constant=\"0.7\"/>\n"
            "    </Combine>\n"
            "  </Masks>\n",
            0.15 * size, 0.1 * rate * emit / (size * size), 1.0 / pow(0.1 * rate * emit / (size * size), 2.0));
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
