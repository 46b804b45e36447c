// test_preset.c: the scenes `weathering init MESH --preset P` generates
// (src/pipeline/preset.c, docs/presets.md): valid scenes that frame the mesh,
// sizes that follow it, and what every preset promises on any model: its
// particles land or leave before the run ends, its output camera looks at the
// side it weathers most, moss grows where it is wet and sheltered, rust
// blooms where it is wet, and old paint cracks and peels.
// test_init.c tests the commands around it (init, run MESH, split).
#define _XOPEN_SOURCE 700 // realpath
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "ensure.h"
#include "run_fixture.h"
#include "io/exr.h"
#include "model/image.h"

// The mean of a texture's channel over an island of texture_cube.obj (first
// covered texel (i0, j0), 224 x 224 texels at 768 x 512; tests/test_texture.c),
// scaled to the texture's size.
static double island_mean(const float *m, int w, int h, int i0, int j0)
{
    double sum = 0.0;
    int n = 0;
    int x0 = i0 * w / 768, y0 = j0 * h / 512, nx = 224 * w / 768, ny = 224 * h / 512;
    for (int j = y0 + 2; j < y0 + ny - 2; ++j) {
        for (int i = x0 + 2; i < x0 + nx - 2; ++i) {
            sum += m[(size_t)j * (size_t)w + (size_t)i];
            n++;
        }
    }
    return n > 0 ? sum / n : 0.0;
}

// Every preset gives a scene the schema accepts and `info` reads, every vertex
// framed; the rain on the cube leaves its dirt on the top, more than on the
// sides, and none underneath.
TEST(presets_make_valid_scenes_and_rain_dirties_the_top)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    static const char *const presets[6] = { "rain", "dust", "soot", "moss", "rust", "old_paint" };
    for (int p = 0; p < 6; ++p) {
        char name[64], path[PATH_MAX + 64];
        snprintf(name, sizeof name, "cube_%s.xml", presets[p]);
        char args[256];
        snprintf(args, sizeof args, "init '%%s' --preset %s --resolution 128 -o %%s", presets[p]);
        ENSURE(run_in(dir, args, data_file("texture_cube.obj"), name) == 0);
        snprintf(path, sizeof path, "%s/%s", dir, name);
        ENSURE(schema_accepts(path));
        ENSURE(run_in(dir, "info %s%s", name, "") == 0);
        ENSURE(strstr(out, "every vertex lies inside an input camera's frame; all inside the "
                           "output camera's") != NULL);
        ENSURE(strstr(out, "texture texture_cube_texture.exr") != NULL);
    }
    ENSURE(run_in(dir, "run %s --out %s -q", "cube_rain.xml", "rain") == 0);
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/rain/texture_cube_texture.exr", dir);
    int w, h;
    float *y = ensure_read_channel(path, "Y", &w, &h);
    ENSURE(y != NULL);
    if (y != NULL) {
        double top = island_mean(y, w, h, 16, 16), bottom = island_mean(y, w, h, 272, 16);
        double side = 0.25 * (island_mean(y, w, h, 528, 16) + island_mean(y, w, h, 16, 272) +
                              island_mean(y, w, h, 272, 272) + island_mean(y, w, h, 528, 272));
        printf("        rain on the cube: top %.4g, sides %.4g, bottom %.4g per square unit\n",
               top, side, bottom);
        ENSURE(top > 0.0 && top > 2.0 * side && bottom == 0.0);
        free(y);
    }
}

// A mesh 100 times larger given in centimetres gets the same scene, every
// length 100 times longer: the same time step, the same number of steps.
TEST(sizes_scale_with_the_mesh)
{
    const char *dir = ensure_tmpdir();
    char *cube = ensure_read_file(data_file("texture_cube.obj"));
    ENSURE(cube != NULL);
    if (cube == NULL) {
        return;
    }
    // Scale the vertices by 100.
    char *big = malloc(strlen(cube) * 2 + 64);
    size_t n = 0;
    for (char *line = strtok(cube, "\n"); line != NULL; line = strtok(NULL, "\n")) {
        double x, yv, z;
        if (strncmp(line, "v ", 2) == 0 && sscanf(line + 2, "%lf %lf %lf", &x, &yv, &z) == 3) {
            n += (size_t)sprintf(big + n, "v %.9g %.9g %.9g\n", 100 * x, 100 * yv, 100 * z);
        } else {
            n += (size_t)sprintf(big + n, "%s\n", line);
        }
    }
    ensure_write_file(dir, "big.obj", big);
    char *small = ensure_read_file(data_file("texture_cube.obj"));
    ensure_write_file(dir, "small.obj", small != NULL ? small : "");
    free(small);
    free(big);
    free(cube);
    ENSURE(run_in(dir, "init small.obj -o %s%s", "small.xml", "") == 0);
    ENSURE(run_in(dir, "init big.obj --units cm -o %s%s", "big.xml", "") == 0);
    char p1[PATH_MAX + 16], p2[PATH_MAX + 16];
    snprintf(p1, sizeof p1, "%s/small.xml", dir);
    snprintf(p2, sizeof p2, "%s/big.xml", dir);
    char *a = ensure_read_file(p1), *b = ensure_read_file(p2);
    ENSURE(a != NULL && b != NULL);
    if (a != NULL && b != NULL) {
        const char *ta = strstr(a, "<Simulation"), *tb = strstr(b, "<Simulation");
        ENSURE(ta != NULL && tb != NULL && strncmp(ta, tb, strcspn(ta, "\n")) == 0);
        const char *ba = strstr(a, "<BoundingBox size=\""), *bb = strstr(b, "<BoundingBox size=\"");
        ENSURE(ba != NULL && bb != NULL);
        if (ba != NULL && bb != NULL) {
            double sa = atof(ba + 19), sb = atof(bb + 19);
            ENSURE_NEAR(sb / sa, 100.0, 1e-3);
        }
        const char *ga = strstr(a, "<Gravity acceleration=\""), *gb = strstr(b, "<Gravity acceleration=\"");
        ENSURE(ga != NULL && gb != NULL);
        if (ga != NULL && gb != NULL) {
            ENSURE_NEAR(atof(gb + 23) / atof(ga + 23), 100.0, 1e-3);
        }
    }
    free(a);
    free(b);
}


// The three numbers after `attr="` (for `<View eye="x y z"`); false when absent.
static bool read_vec3(const char *text, const char *attr, double v[3])
{
    const char *s = strstr(text, attr);
    return s != NULL && sscanf(s + strlen(attr), "%lf %lf %lf", &v[0], &v[1], &v[2]) == 3;
}

// The output camera faces the wind, from 20 to 60 degrees up: rain, soot and
// moss from upwind (soot, blown in from the side, low), dust (no wind) from
// the front right; the comment names the same angles.
TEST(the_output_camera_faces_the_wind)
{
    const char *dir = ensure_tmpdir();
    static const char *const presets[4] = { "rain", "dust", "soot", "moss" };
    for (int p = 0; p < 4; ++p) {
        char name[64], args[256], path[PATH_MAX + 64];
        snprintf(name, sizeof name, "face_%s.xml", presets[p]);
        snprintf(args, sizeof args, "init '%%s' --preset %s --resolution 64 -o %%s", presets[p]);
        ENSURE(run_in(dir, args, data_file("texture_cube.obj"), name) == 0);
        snprintf(path, sizeof path, "%s/%s", dir, name);
        char *text = ensure_read_file(path);
        ENSURE(text != NULL);
        const char *shot = strstr(text, "cameraName=\"shot\"");
        double eye[3], target[3], wind[3] = { 0.0, 0.0, 0.0 };
        bool ok = shot != NULL && read_vec3(shot, "eye=\"", eye) &&
                  read_vec3(shot, "target=\"", target);
        const char *w = strstr(text, "<Wind ");
        if (w != NULL) {
            const char *x = strstr(w, "dirX=\""), *y = strstr(w, "dirY=\""), *z = strstr(w, "dirZ=\"");
            ok = ok && x != NULL && y != NULL && z != NULL;
            if (ok) {
                wind[0] = atof(x + 6);
                wind[1] = atof(y + 6);
                wind[2] = atof(z + 6);
            }
        }
        free(text);
        ENSURE(ok);
        double q[3] = { eye[0] - target[0], eye[1] - target[1], eye[2] - target[2] };
        double ql = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        double elevation = asin(q[1] / ql) * 180.0 / 3.14159265358979323846;
        double hw = sqrt(wind[0] * wind[0] + wind[2] * wind[2]);
        printf("        %s: the camera %.0f degrees up, cos to the upwind side %.3f\n", presets[p],
               elevation, hw > 0.0 ? -(q[0] * wind[0] + q[2] * wind[2]) /
                                         (hw * sqrt(q[0] * q[0] + q[2] * q[2]))
                                   : 0.0);
        ENSURE(elevation >= 20.0 - 0.01 && elevation <= 60.0 + 0.01);
        if (hw > 0.0) {
            // Horizontally straight upwind.
            ENSURE_NEAR(-(q[0] * wind[0] + q[2] * wind[2]) / (hw * sqrt(q[0] * q[0] + q[2] * q[2])),
                        1.0, 1e-6);
        } else {
            ENSURE(q[0] > 0.0 && q[2] > 0.0); // the front right
        }
        ENSURE(strcmp(presets[p], "soot") != 0 || elevation < 30.0);
        ENSURE(strcmp(presets[p], "soot") == 0 || elevation > 50.0);
    }
}

// A lumpy sphere (radius 1 +- 0.45, hollows between its lumps) with
// equal-area UVs (u the longitude, v = (1 + cos(latitude from the top)) / 2),
// so that a texel stands for the same area everywhere and the texture's mean
// over its texels is the surface's mean.
static void write_lumpy_sphere(const char *dir, const char *name)
{
    enum { NT = 24, NP = 48 };
    const double pi = 3.14159265358979323846;
    size_t cap = 256 * (size_t)(NT + 1) * (NP + 1) + 128 * NT * NP, n = 0;
    char *text = malloc(cap);
    if (text == NULL) {
        return;
    }
    for (int i = 0; i <= NT; ++i) {
        for (int j = 0; j <= NP; ++j) {
            double th = pi * i / NT, ph = 2.0 * pi * j / NP;
            double s3 = sin(3.0 * th);
            double r = 1.0 + 0.3 * s3 * s3 * cos(4.0 * ph) + 0.15 * cos(5.0 * th) * sin(3.0 * ph);
            n += (size_t)snprintf(text + n, cap - n, "v %.6f %.6f %.6f\nvt %.6f %.6f\n",
                                  r * sin(th) * cos(ph), r * cos(th), r * sin(th) * sin(ph),
                                  (double)j / NP, 0.5 * (1.0 + cos(th)));
        }
    }
    for (int i = 0; i < NT; ++i) {
        for (int j = 0; j < NP; ++j) {
            int a = i * (NP + 1) + j + 1, b = a + 1, c = a + NP + 1, d = c + 1; // 1-based
            n += (size_t)snprintf(text + n, cap - n, "f %d/%d %d/%d %d/%d\nf %d/%d %d/%d %d/%d\n",
                                  a, a, d, d, c, c, a, a, b, b, d, d);
        }
    }
    ensure_write_file(dir, name, text);
    free(text);
}

// `text` with every `attr="X"` replaced by `attr="X * factor"` (malloc'd).
static char *scale_attribute(const char *text, const char *attr, double factor)
{
    size_t len = strlen(text), n = 0;
    char *res = malloc(len + 1024);
    if (res == NULL) {
        return NULL;
    }
    const char *s = text;
    for (const char *hit; (hit = strstr(s, attr)) != NULL && n + 64 < len + 1024;) {
        hit += strlen(attr);
        memcpy(res + n, s, (size_t)(hit - s));
        n += (size_t)(hit - s);
        char *end;
        double value = strtod(hit, &end);
        n += (size_t)sprintf(res + n, "%.9g", value * factor);
        s = end;
    }
    strcpy(res + n, s);
    return res;
}

// What a preset's run on a mesh gave.
typedef struct preset_run {
    double flying;     // share of the particles still flying at the end
    double mask_mean;  // the main channel's mean over the output camera's mesh pixels
    double texture_mean; // ... over the texture's seen texels
    double moss_low, moss_high; // moss over the least and the most accessible fifth
} preset_run;

// The mean of `values` over `select` > 0 (mask: over the model's pixels, from
// the depth), or NaN.
static double mean_where(const float *values, const float *select, size_t count, bool depth)
{
    double sum = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < count; ++i) {
        bool in = depth ? select[i] > 0.0f && select[i] < 1e30f : select[i] > 0.5f;
        if (in) {
            sum += values[i];
            n++;
        }
    }
    return n > 0 ? sum / (double)n : NAN;
}

static int compare_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

// Moss over the least and the most accessible fifth of the texture's seen
// texels (one texel, one area: the sphere's UVs), by the accessibility channel
// `ao`; texels at the fifths' bounds count in full (many are exactly 1).
static void moss_by_access(const float *moss, const float *ao, const float *seen, size_t count,
                           double *low, double *high)
{
    float *sorted = malloc(count * sizeof *sorted);
    size_t n = 0;
    for (size_t i = 0; sorted != NULL && i < count; ++i) {
        if (seen[i] > 0.5f) {
            sorted[n++] = ao[i];
        }
    }
    *low = *high = NAN;
    if (n >= 10) {
        qsort(sorted, n, sizeof *sorted, compare_float);
        float q20 = sorted[n / 5], q80 = sorted[n - 1 - n / 5];
        double sl = 0.0, sh = 0.0;
        size_t nl = 0, nh = 0;
        for (size_t i = 0; i < count; ++i) {
            if (seen[i] > 0.5f && ao[i] <= q20) {
                sl += moss[i];
                nl++;
            }
            if (seen[i] > 0.5f && ao[i] >= q80) {
                sh += moss[i];
                nh++;
            }
        }
        *low = sl / (double)nl;
        *high = sh / (double)nh;
    }
    free(sorted);
}

// Runs `preset` on dir/mesh (its texture NAME_texture.exr) at 128 texels with
// an eighth of the preset's particles (the shares do not depend on the count);
// with `ao`, an <Accessibility name="ao"> of 64 rays over the shelter's
// distance is added to measure moss by.
static bool run_preset(const char *dir, const char *mesh, const char *base, const char *preset,
                       bool ao, preset_run *res)
{
    char args[512], path[PATH_MAX + 128], scene[64];
    snprintf(scene, sizeof scene, "%s_%s.xml", base, preset);
    snprintf(args, sizeof args, "init %s --preset %s --resolution 128 -o %s --force", mesh,
             preset, scene);
    if (weathering_in(dir, args, true) != 0) {
        return false;
    }
    snprintf(path, sizeof path, "%s/%s", dir, scene);
    char *text = ensure_read_file(path);
    char *fewer = text != NULL ? scale_attribute(text, " rate=\"", 0.125) : NULL;
    free(text);
    if (fewer == NULL) {
        return false;
    }
    if (ao) {
        const char *d = strstr(fewer, "<Accessibility name=\"shelter\"");
        const char *dd = d != NULL ? strstr(d, "distance=\"") : NULL;
        char *end = strstr(fewer, "  </Masks>");
        if (dd == NULL || end == NULL) {
            free(fewer);
            return false;
        }
        char *with = malloc(strlen(fewer) + 256);
        if (with == NULL) {
            free(fewer);
            return false;
        }
        size_t head = (size_t)(end - fewer);
        memcpy(with, fewer, head);
        sprintf(with + head, "    <Accessibility name=\"ao\" rays=\"64\" distance=\"%g\"/>\n%s",
                atof(dd + 10), end);
        free(fewer);
        fewer = with;
    }
    ensure_write_file(dir, scene, fewer);
    free(fewer);
    snprintf(args, sizeof args, "run %s --out %s_%s --stats %s_%s.json -q", scene, base, preset,
             base, preset);
    if (weathering_in(dir, args, true) != 0) {
        return false;
    }
    snprintf(path, sizeof path, "%s/%s_%s.json", dir, base, preset);
    char *json = ensure_read_file(path);
    res->flying = ensure_json_number(json, NULL, "alive") /
                  ensure_json_number(json, NULL, "particles_emitted");
    free(json);
    const char *channel = strcmp(preset, "moss") == 0 ? "moss.Y" : "Y";
    int w = 0, h = 0, w2 = -1, h2 = -1, tw = 0, th = 0, tw2 = -1, th2 = -1;
    snprintf(path, sizeof path, "%s/%s_%s/shot_depth.exr", dir, base, preset);
    float *depth = ensure_read_channel(path, "R|Z", &w, &h);
    snprintf(path, sizeof path, "%s/%s_%s/mask.exr", dir, base, preset);
    float *mask = ensure_read_channel(path, channel, &w2, &h2);
    snprintf(path, sizeof path, "%s/%s_%s/%s_texture.exr", dir, base, preset, base);
    float *tex = ensure_read_channel(path, channel, &tw, &th);
    float *seen = ensure_read_channel(path, "seen", &tw2, &th2);
    float *access = ao ? ensure_read_channel(path, "ao.Y", &tw2, &th2) : NULL;
    bool ok = depth != NULL && mask != NULL && tex != NULL && seen != NULL && w == w2 &&
              h == h2 && tw == tw2 && th == th2 && (!ao || access != NULL);
    if (ok) {
        res->mask_mean = mean_where(mask, depth, (size_t)w * (size_t)h, true);
        res->texture_mean = mean_where(tex, seen, (size_t)tw * (size_t)th, false);
        res->moss_low = res->moss_high = NAN;
        if (ao) {
            moss_by_access(tex, access, seen, (size_t)tw * (size_t)th, &res->moss_low,
                           &res->moss_high);
        }
    }
    free(depth);
    free(mask);
    free(tex);
    free(seen);
    free(access);
    return ok;
}

// Every preset on a lumpy sphere (issue 25): at most 5% of its particles are
// still flying when the run ends (--stats: alive / particles_emitted), and
// its output camera looks at the side it weathers most: the mask's mean over
// the mesh's pixels is at least the texture's mean over its seen texels (the
// surface's mean). For moss, the mask is `moss`.
TEST(every_preset_lands_its_particles_and_faces_its_weathered_side)
{
    SLOW();
    const char *dir = ensure_tmpdir();
    write_lumpy_sphere(dir, "lumpy.obj");
    static const char *const presets[4] = { "rain", "dust", "soot", "moss" };
    for (int p = 0; p < 4; ++p) {
        preset_run res;
        ENSURE(run_preset(dir, "lumpy.obj", "lumpy", presets[p], false, &res));
        printf("        %s: %.2f%% still flying; mask %.4g, texture %.4g (x %.2f)\n", presets[p],
               100.0 * res.flying, res.mask_mean, res.texture_mean,
               res.mask_mean / res.texture_mean);
        ENSURE(res.flying <= 0.05);
        ENSURE(res.texture_mean > 0.0 && res.mask_mean >= res.texture_mean);
    }
}

// Moss grows where it is wet and sheltered: on the lumpy sphere, the moss in
// the least accessible fifth of the surface is at least twice that in the
// most accessible fifth (accessibility from 64 rays, the shelter's distance),
// and there is moss in the hollows.
TEST(moss_grows_where_wet_and_sheltered)
{
    const char *dir = ensure_tmpdir();
    write_lumpy_sphere(dir, "hollows.obj");
    preset_run res;
    ENSURE(run_preset(dir, "hollows.obj", "hollows", "moss", true, &res));
    printf("        moss: %.4g in the least accessible fifth, %.4g in the most\n", res.moss_low,
           res.moss_high);
    ENSURE(res.moss_low > 0.01);
    ENSURE(res.moss_low >= 2.0 * res.moss_high);
}

// Runs the preset `preset` on uv_sphere.obj at 96 texels in dir/NAME
// (NAME.xml, the outputs in dir/NAME/), after checking that the schema
// accepts its scene. False when a step fails.
static bool run_sphere(const char *dir, const char *preset)
{
    char args[256], path[PATH_MAX + 64];
    snprintf(args, sizeof args, "init '%%s' --preset %s --resolution 96 -o %%s --force -q", preset);
    char scene[64];
    snprintf(scene, sizeof scene, "%s.xml", preset);
    if (run_in(dir, args, data_file("uv_sphere.obj"), scene) != 0) {
        return false;
    }
    snprintf(path, sizeof path, "%s/%s", dir, scene);
    if (!schema_accepts(path)) {
        return false;
    }
    return run_in(dir, "run %s --out %s -q", scene, preset) == 0;
}

// Texels of a channel above 0 (-1 when the channel cannot be read).
static long nonzero_texels(const char *path, const char *channel)
{
    int w = 0, h = 0;
    float *v = ensure_read_channel(path, channel, &w, &h);
    if (v == NULL) {
        return -1;
    }
    long n = 0;
    for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
        n += v[i] > 0.0f;
    }
    free(v);
    return n;
}

// The rust preset on a sphere: a valid scene, a frame per spell whose rust
// covers more of the sphere each spell, and rust only where water is (it seeds
// and spreads where the rain's water stays).
TEST(rust_blooms_where_wet_and_grows_each_spell)
{
    SLOW(); // 2.3 s on an idle machine, 8 s on a busy one
    const char *dir = ensure_tmpdir();
    ENSURE(run_sphere(dir, "rust"));
    char path[PATH_MAX + 64];
    long last = 0;
    for (int f = 1; f <= 6; ++f) {
        snprintf(path, sizeof path, "%s/rust/mask.%04d.exr", dir, f);
        long n = nonzero_texels(path, "rust.Y");
        printf("        spell %d: rust on %ld texels\n", f, n);
        ENSURE(n > last);
        last = n;
    }
    snprintf(path, sizeof path, "%s/rust/mask.exr", dir);
    int w = 0, h = 0, w2 = -1, h2 = -1;
    float *rust = ensure_read_channel(path, "rust.Y", &w, &h);
    float *water = ensure_read_channel(path, "water.Y", &w2, &h2);
    ENSURE(rust != NULL && water != NULL && w == w2 && h == h2);
    if (rust != NULL && water != NULL && w == w2 && h == h2) {
        long dry = 0;
        for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
            dry += rust[i] > 0.0f && !(water[i] > 0.0f);
        }
        ENSURE(dry == 0);
    }
    free(rust);
    free(water);
}

// The old_paint preset on a sphere: a valid scene whose mask has crack.Y and
// peel.Y, both somewhere, the peeling growing over the spells, and peel only
// where there is a crack or water (it starts at cracks' edges where wet).
TEST(old_paint_cracks_and_peels_where_wet)
{
    SLOW(); // 2.3 s on an idle machine, 8 s on a busy one
    const char *dir = ensure_tmpdir();
    ENSURE(run_sphere(dir, "old_paint"));
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/old_paint/mask.0001.exr", dir);
    long first = nonzero_texels(path, "peel.Y");
    snprintf(path, sizeof path, "%s/old_paint/mask.exr", dir);
    int w = 0, h = 0, w2 = -1, h2 = -1, w3 = -2, h3 = -2;
    float *crack = ensure_read_channel(path, "crack.Y", &w, &h);
    float *peel = ensure_read_channel(path, "peel.Y", &w2, &h2);
    float *water = ensure_read_channel(path, "water.Y", &w3, &h3);
    ENSURE(crack != NULL && peel != NULL && water != NULL && w == w2 && h == h2 && w == w3 &&
           h == h3);
    if (crack != NULL && peel != NULL && water != NULL && w == w2 && h == h2 && w == w3 &&
        h == h3) {
        long cracked = 0, peeled = 0, stray = 0;
        for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
            cracked += crack[i] > 0.0f;
            peeled += peel[i] > 0.0f;
            stray += peel[i] > 0.0f && !(crack[i] > 0.0f) && !(water[i] > 0.0f);
        }
        printf("        cracked %ld texels, peeled %ld (%ld after the first spell)\n", cracked,
               peeled, first);
        ENSURE(cracked > 0 && peeled > first && first >= 0);
        ENSURE(stray == 0);
    }
    free(crack);
    free(peel);
    free(water);
}

int main(void)
{
    RUN(presets_make_valid_scenes_and_rain_dirties_the_top);
    RUN(sizes_scale_with_the_mesh);
    RUN(the_output_camera_faces_the_wind);
    RUN(every_preset_lands_its_particles_and_faces_its_weathered_side);
    RUN(moss_grows_where_wet_and_sheltered);
    RUN(rust_blooms_where_wet_and_grows_each_spell);
    RUN(old_paint_cracks_and_peels_where_wet);
    return ensure_summary();
}
