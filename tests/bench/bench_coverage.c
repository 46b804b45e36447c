// bench_coverage.c: how much of what a particle could reach a generated scene
// sees (issue 26, item 3), refereed by the exact geometry (Embree 3).
//
// The TextureMap's `seen` (docs/texture.md) leaves out the faces no particle
// or ray can reach: faces buried inside another closed solid of the mesh or
// sealed against one (the default house is overlapping closed boxes). Blender's
// bake covers those too, so its coverage is no fair referee. Here:
//
// - Every shipped mesh with UVs (xml_scenes/meshes/*.obj) is run in a child
//   process as `weathering run MESH --preset rain --resolution R --out NAME`
//   (R = 512, 256 with WX_BENCH_QUICK=1, or WX_BENCH_COVERAGE_PX); init's
//   TextureMap takes the same resolution.
// - The bench loads the scene that run wrote, rebuilds the texture phase's UV
//   raster (wx_textures_prepare: the same mesh, channel, tiles and size) and
//   reads `seen` from the run's texture EXR. Covered texels are those with a
//   triangle (not the padding).
// - A covered texel is reachable when q = p + n * eps (p, n its surface point
//   and normal, eps = 1e-5 of the meshes' bounding-box diagonal, or
//   WX_BENCH_COVERAGE_EPS times it: at 1e-4, 2.4 mm on the house, the point
//   stepped over its 1 mm glass pane and the core's front behind it read
//   reachable, 26 m^2) lies outside
//   every closed solid: the winding number at q, counted along a ray from q to
//   infinity (+1 for every triangle the ray leaves through, -1 for every one
//   it enters, each triangle once), is 0. Three generic directions, majority
//   vote (a ray through an edge or a vertex may count a crossing twice or not
//   at all). The import turns closed parts outwards, so inside is > 0; any
//   non-zero sum counts as inside (an open part gives sums that depend on the
//   direction: the vote settles those, and they are counted as "ambiguous").
//   The texel's point lies on the smooth (Phong) surface the bake draws
//   (wx_uv_raster_point), up to a few texels off the flat triangle where the
//   mesh curves: it is put back on the triangle (projected onto its plane)
//   and steps off along the triangle's normal, else on Spot every concave
//   texel read as inside (7% of its area).
// - Each texel weighs the world area it stands for: its triangle's world area
//   over its UV area, times one texel's UV area.
//
// Reported per mesh, by area and by texel count: the covered area, the share
// of it that is reachable, the share of the reachable area that is `seen`
// (the figure of item 3: >= 0.90 on the default house, >= 0.95 on the other
// shipped models) and the share of the seen area that is unreachable (should
// be about 0). Also that share with the mesh's bottom left out (reachable
// faces turned down, -y against init's gravity, within 10 eps of the mesh's
// lowest point: the house's ground slab underside, which no generated camera
// looks at and rain does not reach), and the area reachable but unseen, and
// seen but unreachable, by the face's outward axis.
//
// WX_BENCH_COVERAGE_REUSE=1 measures the runs the last call left in
// $WX_BUILD/tmp/bench_coverage instead of running them again. Figures go to $WX_BENCH_CSV
// (bench_report.h); exit status 1 only on errors.
#define _XOPEN_SOURCE 700 // realpath
#include <dirent.h>
#include <embree3/rtcore.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_report.h"
#include "bench_run.h"
#include "gather/texture.h"
#include "io/exr.h"
#include "io/mesh_import.h"
#include "io/scene_xml.h"
#include "model/geometry.h"
#include "model/image.h"
#include "model/scene.h"
#include "pipeline/bake_phase.h"
#include "pipeline/pipeline.h"
#include "pipeline/texture_phase.h"

enum { MAX_MESHES = 32, MAX_HITS = 4096, DIRECTIONS = 3 };

// --- the winding number with Embree -------------------------------------------

typedef struct hit {
    unsigned geom, prim;
} hit;

// An intersect context the filter appends every crossing to (then rejects it,
// so the ray runs on to infinity).
typedef struct gather_context {
    struct RTCIntersectContext ctx; // first: the filter casts the context back
    int count;
    bool overflow;
    hit hits[MAX_HITS];
} gather_context;

static void collect_filter(const struct RTCFilterFunctionNArguments *args)
{
    gather_context *g = (gather_context *)args->context;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) {
            continue;
        }
        // RTCHitN_primID and _geomID are C++ only: the SOA layout of rtcore_ray.h.
        unsigned prim = ((const unsigned *)args->hit)[5 * args->N + i];
        unsigned geom = ((const unsigned *)args->hit)[6 * args->N + i];
        bool known = false;
        for (int k = 0; k < g->count && !known; ++k) {
            known = g->hits[k].geom == geom && g->hits[k].prim == prim;
        }
        if (!known) {
            if (g->count < MAX_HITS) {
                g->hits[g->count++] = (hit){ geom, prim };
            } else {
                g->overflow = true;
            }
        }
        args->valid[i] = 0;
    }
}

typedef struct exact {
    RTCDevice device;
    RTCScene scene;
    int count;
    const wx_mesh_data *meshes[MAX_MESHES]; // by geomID
} exact;

static void exact_free(exact *e)
{
    if (e->scene != NULL) {
        rtcReleaseScene(e->scene);
    }
    if (e->device != NULL) {
        rtcReleaseDevice(e->device);
    }
    memset(e, 0, sizeof *e);
}

static bool exact_build(exact *e, const wx_geometry *geometry)
{
    memset(e, 0, sizeof *e);
    e->device = rtcNewDevice("threads=2");
    e->scene = e->device != NULL ? rtcNewScene(e->device) : NULL;
    if (e->scene == NULL || geometry->count > MAX_MESHES) {
        return false;
    }
    rtcSetSceneFlags(e->scene, RTC_SCENE_FLAG_ROBUST);
    for (int m = 0; m < geometry->count; ++m) {
        const wx_mesh_data *mesh = &geometry->meshes[m].data;
        if (mesh->positions == NULL || mesh->indices == NULL) {
            return false;
        }
        RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                           3 * sizeof(float), (size_t)mesh->vertex_count);
        unsigned *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                              3 * sizeof(unsigned), (size_t)mesh->triangle_count);
        if (v == NULL || t == NULL) {
            rtcReleaseGeometry(g);
            return false;
        }
        for (int64_t i = 0; i < mesh->vertex_count; ++i) {
            for (int k = 0; k < 3; ++k) {
                v[3 * i + k] = (float)((double)mesh->positions[3 * i + k] + mesh->origin[k]);
            }
        }
        memcpy(t, mesh->indices, (size_t)mesh->triangle_count * 3 * sizeof(unsigned));
        rtcSetGeometryIntersectFilterFunction(g, collect_filter);
        rtcCommitGeometry(g);
        unsigned id = rtcAttachGeometry(e->scene, g);
        rtcReleaseGeometry(g);
        if (id >= MAX_MESHES) {
            return false;
        }
        e->meshes[id] = mesh;
        e->count = m + 1;
    }
    rtcCommitScene(e->scene);
    return true;
}

// (b - a) x (c - a) of a triangle: the side its winding calls outside.
static void triangle_normal(const wx_mesh_data *mesh, int64_t tri, double n[3])
{
    const uint32_t *idx = &mesh->indices[3 * tri];
    const float *a = &mesh->positions[3 * (size_t)idx[0]];
    const float *b = &mesh->positions[3 * (size_t)idx[1]];
    const float *c = &mesh->positions[3 * (size_t)idx[2]];
    double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
    double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

// The winding number at q along direction d: crossings leaving minus entering.
static int winding(const exact *e, const double q[3], const double d[3], bool *overflow)
{
    gather_context g;
    rtcInitIntersectContext(&g.ctx);
    g.count = 0;
    g.overflow = false;
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = (float)q[0];
    rh.ray.org_y = (float)q[1];
    rh.ray.org_z = (float)q[2];
    rh.ray.dir_x = (float)d[0];
    rh.ray.dir_y = (float)d[1];
    rh.ray.dir_z = (float)d[2];
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = INFINITY;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(e->scene, &g.ctx, &rh);
    int sum = 0;
    for (int k = 0; k < g.count; ++k) {
        double n[3];
        triangle_normal(e->meshes[g.hits[k].geom], g.hits[k].prim, n);
        double s = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        sum += s > 0 ? 1 : s < 0 ? -1 : 0;
    }
    *overflow = *overflow || g.overflow;
    return sum;
}

// --- one run measured -----------------------------------------------------------

typedef struct tally {
    double n, a; // texels, area
} tally;

typedef struct coverage {
    tally covered, reachable, seen, seen_reachable, seen_unreachable;
    /// The mesh's bottom: reachable texels on faces turned down (-y, against
    /// init's gravity) at the mesh's lowest level, where no camera looks.
    tally bottom, seen_bottom;
    int64_t ambiguous;   ///< texels whose three rays did not agree
    int64_t winding_neg; ///< texels with a negative sum on a majority of rays
    int64_t flipped;     ///< texels whose shading normal faces away from their triangle's winding
    /// By the face's outward axis (+x, -x, +y, -y, +z, -z): the area reachable
    /// but not seen, and seen but not reachable.
    double unseen_by_axis[6], unreachable_by_axis[6];
    bool overflow;
    double seconds;
} coverage;

static const char *const AXES[6] = { "+x", "-x", "+y", "-y", "+z", "-z" };

static int outward_axis(const double fn[3], double side)
{
    int best = 0;
    for (int k = 1; k < 3; ++k) {
        best = fabs(fn[k]) > fabs(fn[best]) ? k : best;
    }
    return 2 * best + (side * fn[best] < 0);
}

static void add(tally *t, double area)
{
    t->n += 1.0;
    t->a += area;
}

// Measures the texture file `file` of target `t` against `e`.
static bool measure_file(const exact *e, const wx_texture_target *t, const wx_texture_file *file,
                         const char *path, double eps, double floor_y, coverage *c)
{
    const wx_uv_raster *ras = &file->raster;
    const wx_mesh_data *mesh = &t->mesh;
    const int uv = t->def->uv;
    const char *wanted[1] = { "seen" };
    wx_image image;
    wx_error err;
    memset(&image, 0, sizeof image);
    if (wx_exr_read(path, wanted, 1, &image, &err) != WX_OK) {
        fprintf(stderr, "bench_coverage: %s\n", err.message);
        return false;
    }
    if (image.width != ras->width || image.height != ras->height) {
        fprintf(stderr, "bench_coverage: %s is %dx%d, the raster %dx%d\n", path, image.width,
                image.height, ras->width, ras->height);
        wx_image_free(&image);
        return false;
    }
    // World area per UV area of every triangle.
    double *ratio = malloc((size_t)mesh->triangle_count * sizeof *ratio + 1);
    if (ratio == NULL) {
        wx_image_free(&image);
        return false;
    }
    for (int64_t k = 0; k < mesh->triangle_count; ++k) {
        double n[3];
        triangle_normal(mesh, k, n);
        const uint32_t *idx = &mesh->indices[3 * k];
        const float *a = &mesh->uvs[uv][2 * (size_t)idx[0]];
        const float *b = &mesh->uvs[uv][2 * (size_t)idx[1]];
        const float *cc = &mesh->uvs[uv][2 * (size_t)idx[2]];
        double uv_area = 0.5 * fabs(((double)b[0] - a[0]) * ((double)cc[1] - a[1]) -
                                    ((double)b[1] - a[1]) * ((double)cc[0] - a[0]));
        double area = 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        ratio[k] = uv_area > 0 ? area / uv_area : 0.0;
    }
    const double texel_uv = 1.0 / ((double)ras->width * (double)ras->height);
    static const double dirs_raw[DIRECTIONS][3] = { { 0.31, 0.87, 0.38 },
                                                    { -0.73, 0.29, 0.62 },
                                                    { 0.45, -0.52, -0.73 } };
    double dirs[DIRECTIONS][3];
    for (int r = 0; r < DIRECTIONS; ++r) {
        const double *v = dirs_raw[r];
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; ++k) {
            dirs[r][k] = v[k] / len;
        }
    }
    const size_t texels = (size_t)ras->width * (size_t)ras->height;
    for (size_t i = 0; i < texels; ++i) {
        int32_t tri = ras->triangle[i];
        double p[3];
        float n[3];
        if (tri < 0 || !wx_uv_raster_point(mesh, uv, ras, i, p, n)) {
            continue;
        }
        double area = ratio[tri] * texel_uv;
        // p lies on the smooth (Phong) surface the bake draws, which leaves
        // the flat triangle by up to a few texels where the mesh curves: put
        // it back on the triangle Embree holds, and step off along the
        // triangle's normal (turned to the side the shading normal says).
        double fn[3], pa[3];
        triangle_normal(mesh, tri, fn);
        const uint32_t *corner = &mesh->indices[3 * (size_t)tri];
        double len = sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
        for (int k = 0; k < 3; ++k) {
            fn[k] /= len;
            pa[k] = p[k] - (mesh->positions[3 * (size_t)corner[0] + k] + mesh->origin[k]);
        }
        double off = pa[0] * fn[0] + pa[1] * fn[1] + pa[2] * fn[2];
        double side = fn[0] * n[0] + fn[1] * n[1] + fn[2] * n[2] < 0 ? -1.0 : 1.0;
        c->flipped += side < 0;
        double q[3];
        for (int k = 0; k < 3; ++k) {
            q[k] = p[k] - off * fn[k] + side * eps * fn[k];
        }
        int inside = 0, negative = 0;
        for (int r = 0; r < DIRECTIONS; ++r) {
            int w = winding(e, q, dirs[r], &c->overflow);
            inside += w != 0;
            negative += w < 0;
        }
        bool reachable = 2 * inside < DIRECTIONS;
        bool seen = image.channels[0][i] > 0.5f;
        c->ambiguous += inside != 0 && inside != DIRECTIONS;
        c->winding_neg += 2 * negative > DIRECTIONS;
        add(&c->covered, area);
        if (reachable) {
            add(&c->reachable, area);
        }
        if (seen) {
            add(&c->seen, area);
            add(reachable ? &c->seen_reachable : &c->seen_unreachable, area);
        }
        if (reachable && outward_axis(fn, side) == 3 && p[1] < floor_y + 10 * eps) {
            add(&c->bottom, area);
            if (seen) {
                add(&c->seen_bottom, area);
            }
        }
        if (seen != reachable) {
            double *by = seen ? c->unreachable_by_axis : c->unseen_by_axis;
            by[outward_axis(fn, side)] += area;
        }
    }
    free(ratio);
    wx_image_free(&image);
    return true;
}

// Loads the scene the run wrote into `out_dir` and measures its TextureMaps.
static bool measure(const char *out_dir, coverage *c)
{
    memset(c, 0, sizeof *c);
    double t0 = bench_now_s();
    char path[PATH_MAX + 64];
    if (snprintf(path, sizeof path, "%s/scene.xml", out_dir) >= (int)sizeof path) {
        return false;
    }
    wx_scene scene;
    wx_geometry geometry;
    wx_textures textures;
    memset(&geometry, 0, sizeof geometry);
    memset(&textures, 0, sizeof textures);
    wx_error err;
    if (wx_scene_load(path, &scene, &err) != WX_OK) {
        fprintf(stderr, "bench_coverage: %s\n", err.message);
        return false;
    }
    wx_run_def opts = wx_default_run_def(&scene);
    opts.quiet = true;
    opts.threads = 2;
    exact e;
    memset(&e, 0, sizeof e);
    bool ok = wx_geometry_load(&scene, true, &geometry, &err) == WX_OK;
    if (ok) {
        wx_textures_find_tiles(&scene, &geometry);
        ok = wx_textures_prepare(&scene, &geometry, &opts, &textures, &err) == WX_OK;
    }
    if (!ok) {
        fprintf(stderr, "bench_coverage: %s\n", err.message);
    }
    ok = ok && textures.count > 0;
    if (ok && !exact_build(&e, &geometry)) {
        fprintf(stderr, "bench_coverage: Embree could not take the meshes\n");
        ok = false;
    }
    double lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    for (int m = 0; ok && m < geometry.count; ++m) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], geometry.meshes[m].data.bounds_min[k]);
            hi[k] = fmax(hi[k], geometry.meshes[m].data.bounds_max[k]);
        }
    }
    const char *eps_env = getenv("WX_BENCH_COVERAGE_EPS");
    const double eps_rel = eps_env != NULL && atof(eps_env) > 0 ? atof(eps_env) : 1e-5;
    double eps =
        eps_rel * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (int i = 0; ok && i < textures.count; ++i) {
        const wx_texture_target *t = &textures.items[i];
        for (int f = 0; ok && f < t->file_count; ++f) {
            char own[WX_PATH_MAX];
            if (t->files[f].udim >= 0) {
                wx_tile_name(t->def->file, t->files[f].udim, own, sizeof own);
            } else {
                snprintf(own, sizeof own, "%s", t->def->file);
            }
            ok = snprintf(path, sizeof path, "%s/%s", out_dir, own) < (int)sizeof path &&
                 measure_file(&e, t, &t->files[f], path, eps, lo[1], c);
        }
    }
    exact_free(&e);
    wx_textures_free(&textures);
    wx_geometry_free(&geometry);
    wx_scene_free(&scene);
    c->seconds = bench_now_s() - t0;
    return ok;
}

// --- the shipped meshes -----------------------------------------------------------

static int compare_names(const void *a, const void *b)
{
    return strcmp((const char *)a, (const char *)b);
}

static double share(double part, double whole)
{
    return whole > 0 ? part / whole : 0.0;
}

static bool one_mesh(const char *program, const char *dir, const char *mesh_path, const char *name,
                     int px)
{
    char abs[PATH_MAX], args[PATH_MAX + 512], out[PATH_MAX + 512];
    if (realpath(mesh_path, abs) == NULL ||
        snprintf(args, sizeof args, "run '%s' --preset rain --resolution %d --out '%s'", abs, px,
                 name) >= (int)sizeof args ||
        snprintf(out, sizeof out, "%s/%s/scene.xml", dir, name) >= (int)sizeof out) {
        return false;
    }
    FILE *done = bench_env_long("WX_BENCH_COVERAGE_REUSE", 0) == 1 ? fopen(out, "r") : NULL;
    double t0 = bench_now_s();
    if (done != NULL) {
        fclose(done); // measured again as the last run left it
    } else {
        char *stats = bench_run(program, dir, args);
        if (stats == NULL) {
            return false;
        }
        free(stats);
    }
    double run_s = bench_now_s() - t0;
    if (snprintf(out, sizeof out, "%s/%s", dir, name) >= (int)sizeof out) {
        return false;
    }
    coverage c;
    if (!measure(out, &c)) {
        return false;
    }
    bool house = strcmp(name, "building") == 0;
    const char *target = house ? ">= 0.90" : ">= 0.95";
    double goal = house ? 0.90 : 0.95;
    double seen_reach_a = share(c.seen_reachable.a, c.reachable.a);
    double seen_reach_n = share(c.seen_reachable.n, c.reachable.n);
    printf("  %-10s covered %.0f texels, %.4g m^2 (run %.1f s, measure %.1f s)\n", name,
           c.covered.n, c.covered.a, run_s, c.seconds);
    printf("    reachable of covered: %.4f by area, %.4f by texels\n",
           share(c.reachable.a, c.covered.a), share(c.reachable.n, c.covered.n));
    printf("    seen of covered:      %.4f by area, %.4f by texels\n", share(c.seen.a, c.covered.a),
           share(c.seen.n, c.covered.n));
    printf("    seen of reachable:    %.4f by area, %.4f by texels (target %s)\n", seen_reach_a,
           seen_reach_n, target);
    printf("    seen but unreachable: %.4f of the seen area, %.4f of the seen texels\n",
           share(c.seen_unreachable.a, c.seen.a), share(c.seen_unreachable.n, c.seen.n));
    printf("    rays disagreeing: %lld texels; negative winding: %lld; normal against the "
           "winding: %lld%s\n",
           (long long)c.ambiguous, (long long)c.winding_neg, (long long)c.flipped,
           c.overflow ? "; SOME RAY CROSSED MORE THAN 4096 TRIANGLES" : "");
    double above_a = share(c.seen_reachable.a - c.seen_bottom.a, c.reachable.a - c.bottom.a);
    double above_n = share(c.seen_reachable.n - c.seen_bottom.n, c.reachable.n - c.bottom.n);
    printf("    the mesh's bottom (turned down at its lowest level): %.4f of the reachable area, "
           "%.4f of it seen; the rest seen %.4f by area, %.4f by texels\n",
           share(c.bottom.a, c.reachable.a), share(c.seen_bottom.a, c.bottom.a), above_a, above_n);
    printf("    reachable unseen / seen unreachable, by the face's outward axis (share of "
           "the reachable / seen area):");
    for (int k = 0; k < 6; ++k) {
        printf(" %s %.4f/%.4f", AXES[k], share(c.unseen_by_axis[k], c.reachable.a),
               share(c.unreachable_by_axis[k], c.seen.a));
    }
    printf("\n");
    fflush(stdout);
    const char *b = "coverage";
    bench_row(b, "covered area", c.covered.a, "mesh unit^2", NULL, false, "%s %d px", name, px);
    bench_row(b, "covered texels", c.covered.n, "texels", NULL, false, "%s %d px", name, px);
    bench_row(b, "reachable share of covered area", share(c.reachable.a, c.covered.a), "ratio",
              NULL, false, "%s %d px", name, px);
    bench_row(b, "reachable share of covered texels", share(c.reachable.n, c.covered.n), "ratio",
              NULL, false, "%s %d px", name, px);
    bench_row(b, "seen share of reachable area", seen_reach_a, "ratio", target,
              seen_reach_a >= goal, "%s %d px", name, px);
    bench_row(b, "seen share of reachable texels", seen_reach_n, "ratio", NULL, false, "%s %d px",
              name, px);
    bench_row(b, "bottom share of reachable area", share(c.bottom.a, c.reachable.a), "ratio", NULL,
              false, "%s %d px", name, px);
    bench_row(b, "seen share of reachable area above the bottom", above_a, "ratio", NULL, false,
              "%s %d px", name, px);
    bench_row(b, "seen share of reachable texels above the bottom", above_n, "ratio", NULL, false,
              "%s %d px", name, px);
    bench_row(b, "seen but unreachable share of seen area", share(c.seen_unreachable.a, c.seen.a),
              "ratio", NULL, false, "%s %d px", name, px);
    bench_row(b, "seen but unreachable share of seen texels", share(c.seen_unreachable.n, c.seen.n),
              "ratio", NULL, false, "%s %d px", name, px);
    bench_row(b, "texels whose rays disagree", (double)c.ambiguous, "texels", NULL, false,
              "%s %d px", name, px);
    return !c.overflow;
}

int main(void)
{
    bool quick = bench_env_long("WX_BENCH_QUICK", 0) == 1;
    int px = (int)bench_env_long("WX_BENCH_COVERAGE_PX", quick ? 256 : 512);
    printf("coverage: the seen share of what a particle can reach, by Embree (issue 26, item 3)\n");
    fflush(stdout);
    char program[PATH_MAX], dir[PATH_MAX];
    if (!bench_workdir("bench_coverage", program, dir)) {
        return 1;
    }
    const char *meshes = "xml_scenes/meshes";
    DIR *d = opendir(meshes);
    if (d == NULL) {
        fprintf(stderr, "bench_coverage: no %s (run from the repository's root)\n", meshes);
        return 1;
    }
    static char names[64][256];
    int count = 0;
    for (struct dirent *de; (de = readdir(d)) != NULL && count < 64;) {
        size_t len = strlen(de->d_name);
        if (len > 4 && len < sizeof names[0] && strcmp(de->d_name + len - 4, ".obj") == 0) {
            snprintf(names[count++], sizeof names[0], "%s", de->d_name);
        }
    }
    closedir(d);
    qsort(names, (size_t)count, sizeof names[0], compare_names);
    bool ok = true;
    for (int i = 0; i < count; ++i) {
        char path[PATH_MAX], name[256];
        if (snprintf(path, sizeof path, "%s/%s", meshes, names[i]) >= (int)sizeof path) {
            continue;
        }
        snprintf(name, sizeof name, "%.*s", (int)strlen(names[i]) - 4, names[i]);
        // Only a mesh with UVs gets a TextureMap from init.
        wx_mesh_data mesh;
        wx_error err;
        memset(&mesh, 0, sizeof mesh);
        bool has_uvs = wx_mesh_import_uvs(path, 1u, &mesh, &err) == WX_OK && mesh.uvs[0] != NULL;
        wx_mesh_data_free(&mesh);
        if (!has_uvs) {
            printf("  %-10s no UVs: skipped\n", name);
            continue;
        }
        if (!one_mesh(program, dir, path, name, px)) {
            fprintf(stderr, "bench_coverage: %s could not be measured\n", name);
            ok = false;
        }
    }
    return ok ? 0 : 1;
}
