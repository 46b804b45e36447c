// bench_embree.c: the exact-geometry reference for the projected-maps collider
// (issue 7). The same step segments are asked of the depth-map collider and of
// Embree 3 (a ray query along the segment against the mesh triangles).
//
// (a) Accuracy, on the shipped scenes (xml_scenes/building.xml, baked here from
//     its mesh; xml_scenes/thesis_box.xml, whose pre-rendered maps show a 2 m
//     cube on a slab, given to Embree as the same two boxes). Particles start on
//     a hemisphere around the geometry, aimed at a random point of its bounds,
//     at speeds from about 0.5 to 80 texels per step, and fly under the scene's
//     gravity and wind (turbulence left out: it does not change what a segment
//     is asked). Each flies until the first step where the collider or the mesh
//     reports a hit, or until it leaves the scene's bounding box (it escapes). When only one of them does, the flight goes on (ignoring
//     that hit) for up to 3 more steps to see whether the other one reports it
//     late. Reported: distance between the two hit points in texels of the hit
//     camera (median, 95th, 99th percentile); missed collisions (the mesh is hit,
//     the collider never sees it) and phantom collisions (the collider hits, the
//     mesh is never hit) in percent of the particles that hit anything, with the
//     missed ones split by speed at 50 texels per step.
// (b) Speed: UV spheres of about 10k, 100k and 1M triangles, baked by three
//     1024-pixel cameras; one million segments starting anywhere in the frames'
//     cube outside the sphere, falling steeply, on 2 threads, of two lengths:
//     1% of the scene's size (10 texels, as PERFORMANCE.md measured Embree) and
//     1.5 texels (the drops of bench_simulate, 3 m/s at dt 0.01). Ours: the
//     simulator's path (vectorised coarse test of 16 segments, the swept test on
//     what it does not clear). Embree: rtcIntersect1 with tfar = segment length.
//     Medians of 3 runs; BVH build time and memory; the maps' memory does not
//     depend on the mesh.
// (c) Where rain lands (issue 26, item 5): the shipped house's box emitter
//     without wind or turbulence, every drop absorbed at its first hit; the
//     collider's and Embree's first hits on the same segments counted per face
//     (material and outward axis; the collider's point put on the nearest
//     triangle), and how many of the collider's hits are recorded with a normal
//     more than 45 degrees off the face they lie on.
//
// Figures go to $WX_BENCH_CSV (bench_report.h); exit status 1 only on errors.
#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "raster/bake.h"
#include "bench_report.h"
#include "sim/collider.h"
#include "sim/force_field.h"
#include "model/maps.h"
#include "model/mesh.h"
#include "sim/emitter.h"
#include "sim/particles.h"
#include "pipeline/pipeline.h"
#include "model/scene.h"
#include "io/maps_file.h"
#include "io/mesh_import.h"
#include "io/scene_xml.h"
#include "pipeline/bake_phase.h"
#include "pipeline/outputs.h"

static const double PI = 3.14159265358979323846;
enum { THREADS = 2 };

// --- the exact side: Embree --------------------------------------------------

typedef struct exact {
    RTCDevice device;
    RTCScene scene;
    int64_t triangles;
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

static bool exact_init(exact *e)
{
    memset(e, 0, sizeof *e);
    e->device = rtcNewDevice("threads=2");
    if (e->device == NULL) {
        return false;
    }
    e->scene = rtcNewScene(e->device);
    return e->scene != NULL;
}

// Adds a triangle mesh: `positions` (3 floats per vertex) plus `origin`.
static bool exact_add(exact *e, const float *positions, const double origin[3], int64_t nv,
                      const uint32_t *indices, int64_t nt)
{
    RTCGeometry g = rtcNewGeometry(e->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), (size_t)nv);
    unsigned *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                          3 * sizeof(unsigned), (size_t)nt);
    if (v == NULL || t == NULL) {
        rtcReleaseGeometry(g);
        return false;
    }
    for (int64_t i = 0; i < nv; ++i) {
        for (int k = 0; k < 3; ++k) {
            v[3 * i + k] = (float)((double)positions[3 * i + k] + origin[k]);
        }
    }
    memcpy(t, indices, (size_t)nt * 3 * sizeof(unsigned));
    rtcCommitGeometry(g);
    rtcAttachGeometry(e->scene, g);
    rtcReleaseGeometry(g);
    e->triangles += nt;
    return true;
}

// Two triangles per face of an axis-aligned box, wound outwards.
static bool exact_add_box(exact *e, const float lo[3], const float hi[3])
{
    float p[24];
    for (int c = 0; c < 8; ++c) {
        p[3 * c] = (c & 1) ? hi[0] : lo[0];
        p[3 * c + 1] = (c & 2) ? hi[1] : lo[1];
        p[3 * c + 2] = (c & 4) ? hi[2] : lo[2];
    }
    static const uint32_t idx[36] = { 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                      2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5 };
    const double zero[3] = { 0, 0, 0 };
    return exact_add(e, p, zero, 8, idx, 12);
}

static void exact_commit(exact *e)
{
    rtcCommitScene(e->scene);
}

// The first hit of the segment p0 -> p1: its parameter s in [0, 1] and, when
// `triangle` is not NULL, the triangle's primID.
static bool exact_hit_triangle(const exact *e, const float p0[3], const float p1[3], float *s,
                               int64_t *triangle)
{
    float d[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
    float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (len <= 0.0f) {
        return false;
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    memset(&rh, 0, sizeof rh);
    rh.ray.org_x = p0[0];
    rh.ray.org_y = p0[1];
    rh.ray.org_z = p0[2];
    rh.ray.dir_x = d[0] / len;
    rh.ray.dir_y = d[1] / len;
    rh.ray.dir_z = d[2] / len;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = len;
    rh.ray.mask = 0xFFFFFFFFu;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(e->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        return false;
    }
    *s = rh.ray.tfar / len;
    if (triangle != NULL) {
        *triangle = (int64_t)rh.hit.primID;
    }
    return true;
}

static bool exact_hit(const exact *e, const float p0[3], const float p1[3], float *s)
{
    return exact_hit_triangle(e, p0, p1, s, NULL);
}

// --- the depth-map side ------------------------------------------------------

typedef struct maps_world {
    wx_scene scene;
    bool scene_loaded;
    int count;
    wx_camera cams[WX_MAX_INPUT_CAMERAS];
    wx_maps maps[WX_MAX_INPUT_CAMERAS];
    wx_collider collider;
    bool collider_ready;
    wx_forces forces;
    bool forces_ready;
    float texel_ws; ///< texel size of the first camera
    int cam_list[WX_MAX_INPUT_CAMERAS];
} maps_world;

static void maps_world_free(maps_world *w)
{
    if (w->collider_ready) {
        wx_collider_free(&w->collider);
    }
    for (int c = 0; c < w->count; ++c) {
        wx_maps_free(&w->maps[c]);
    }
    if (w->forces_ready) {
        wx_forces_free(&w->forces);
    }
    if (w->scene_loaded) {
        wx_scene_free(&w->scene);
    }
    memset(w, 0, sizeof *w);
}

// Loads the input cameras' depth, normal and impact maps of a loaded scene (whose
// map paths point at files) and builds the collider and the forces.
static bool maps_world_finish(maps_world *w)
{
    wx_error err;
    for (int c = 0; c < w->scene.camera_count; ++c) {
        const wx_scene_camera *sc = &w->scene.cameras[c];
        if (sc->is_output) {
            continue;
        }
        if (wx_maps_load_layers(&w->maps[w->count],
                                WX_MAPS_DEPTH | WX_MAPS_NORMAL | WX_MAPS_IMPACT, 1, &w->scene,
                                sc->layers, sc->depth_path, sc->normal_path, sc->impact_path,
                                NULL, &err) != WX_OK) {
            fprintf(stderr, "bench_embree: %s\n", err.message);
            return false;
        }
        w->cams[w->count] = sc->camera;
        w->cam_list[w->count] = w->count;
        w->count++;
    }
    if (wx_collider_init(&w->collider, w->cams, w->maps, w->count, false, &err) != WX_OK) {
        fprintf(stderr, "bench_embree: %s\n", err.message);
        return false;
    }
    w->collider_ready = true;
    w->texel_ws = w->collider.cameras[0].texel_ws;
    if (wx_forces_init(&w->forces, w->scene.fields, w->scene.field_count, w->scene.seed,
                       &err) != WX_OK) {
        fprintf(stderr, "bench_embree: %s\n", err.message);
        return false;
    }
    w->forces_ready = true;
    return true;
}

// Loads a scene and bakes what it needs baking into `out_dir`.
static bool maps_world_load(maps_world *w, const char *scene_path, const char *out_dir,
                            int layers)
{
    memset(w, 0, sizeof *w);
    wx_error err;
    if (wx_scene_load(scene_path, &w->scene, &err) != WX_OK) {
        fprintf(stderr, "bench_embree: %s\n", err.message);
        return false;
    }
    w->scene_loaded = true;
    for (int c = 0; layers > 0 && c < w->scene.camera_count; ++c) {
        if (!w->scene.cameras[c].is_output) {
            w->scene.cameras[c].layers = layers; // docs/design.md section 14
        }
    }
    wx_run_def opts;
    opts = wx_default_run_def(&w->scene);
    snprintf(opts.out_dir, sizeof opts.out_dir, "%s", out_dir);
    opts.threads = THREADS;
    opts.quiet = true;
    if (w->scene.mesh_count > 0 &&
        (wx_output_prepare(&w->scene, &opts, NULL, &err) != WX_OK || wx_bake_scene(&w->scene, &opts, &err) != WX_OK ||
         wx_use_baked_maps(&w->scene, &opts, &err) != WX_OK)) {
        fprintf(stderr, "bench_embree: %s\n", err.message);
        return false;
    }
    return maps_world_finish(w);
}

// The collider's answer for one segment, as the simulator asks it.
static bool maps_hit(const maps_world *w, const float p0[3], const float p1[3], wx_hit *hit)
{
    return !wx_collider_coarse_clear(&w->collider, p0, p1) &&
           wx_collider_sweep(&w->collider, p0, p1, hit);
}

// --- (a) accuracy -------------------------------------------------------------

typedef struct accuracy {
    double *error_texels; ///< per particle hit by both
    int64_t both, missed, phantom, neither, segments;
    /// Missed where a map records the surface (a point just beyond the exact hit
    /// is in the collision set): tunnelling, which the swept test must prevent;
    /// split by speed at 50 texels per step. The other misses are hits within a
    /// texel of a silhouette that no map records at its resolution.
    int64_t missed_recorded_slow, missed_recorded_fast;
    /// Phantom hits below the geometry's lowest point: particles that passed the
    /// edge of the ground and moved under it, where only the top camera informs
    /// and says "behind" (docs/design.md section 4's rule for uninformed cameras).
    int64_t phantom_below;
    double max_speed_texels;
} accuracy;

static float uniform(uint64_t *state)
{
    *state = wx_mix64(*state + UINT64_C(0x9e3779b97f4a7c15));
    return (float)(*state >> 40) * (1.0f / 16777216.0f);
}

// Flies `n` particles at the geometry within bounds lo..hi (see the header).
static bool measure_accuracy(const maps_world *w, const exact *e, const float lo[3],
                             const float hi[3], int n, accuracy *a)
{
    memset(a, 0, sizeof *a);
    a->error_texels = malloc((size_t)n * sizeof(double));
    if (a->error_texels == NULL) {
        return false;
    }
    float centre[3], radius = 0.0f;
    for (int k = 0; k < 3; ++k) {
        centre[k] = 0.5f * (lo[k] + hi[k]);
        radius += 0.25f * (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    radius = 1.2f * sqrtf(radius);
    float dt = (float)w->scene.time_step;
    float texel = w->texel_ws;
    float acc[3];
    for (int k = 0; k < 3; ++k) {
        acc[k] = w->forces.gravity[k] + w->forces.wind[k]; // mass 1
    }
    uint64_t state = 7;
    for (int i = 0; i < n; ++i) {
        // Start on the upper hemisphere, aim at a point of the bounds.
        float p[3], d[3], aim[3];
        float z = uniform(&state), phi = 2.0f * (float)PI * uniform(&state);
        float rxy = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        d[0] = rxy * cosf(phi);
        d[1] = z;
        d[2] = rxy * sinf(phi);
        for (int k = 0; k < 3; ++k) {
            p[k] = centre[k] + radius * d[k];
            aim[k] = lo[k] + (hi[k] - lo[k]) * uniform(&state);
        }
        if (wx_collider_point_collides(&w->collider, p)) {
            --i; // a start behind a surface says nothing
            continue;
        }
        float dir[3] = { aim[0] - p[0], aim[1] - p[1], aim[2] - p[2] };
        float len = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
        // Speed: log-uniform from 0.5 to 80 texels per step.
        float texels_per_step = 0.5f * powf(160.0f, uniform(&state));
        float speed = texels_per_step * texel / dt;
        float v[3] = { speed * dir[0] / len, speed * dir[1] / len, speed * dir[2] / len };
        float maps_s = -1.0f, exact_s = -1.0f, maps_point[3] = { 0 }, exact_point[3] = { 0 };
        float step_texels = 0.0f, exact_dir[3] = { 0, 0, 0 };
        int after_first = -1; // steps since the first report
        int max_steps = (int)(4.0f * radius / (speed * dt)) + 10;
        for (int step = 0; step < max_steps; ++step) {
            float q[3];
            for (int k = 0; k < 3; ++k) {
                v[k] += dt * acc[k];
                q[k] = p[k] + dt * v[k];
            }
            a->segments++;
            float seg = sqrtf((q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                              (q[2] - p[2]) * (q[2] - p[2])) /
                        texel;
            wx_hit hit;
            float s;
            if (maps_s < 0.0f && maps_hit(w, p, q, &hit)) {
                maps_s = (float)step + hit.s;
                memcpy(maps_point, hit.point, sizeof maps_point);
            }
            if (exact_s < 0.0f && exact_hit(e, p, q, &s)) {
                exact_s = (float)step + s;
                for (int k = 0; k < 3; ++k) {
                    exact_point[k] = p[k] + s * (q[k] - p[k]);
                    exact_dir[k] = (q[k] - p[k]) / (seg * texel);
                }
                step_texels = seg;
            }
            if (maps_s >= 0.0f && exact_s >= 0.0f) {
                break;
            }
            bool in_box = true;
            for (int k = 0; k < 3; ++k) {
                in_box = in_box && fabsf(q[k] - w->scene.bbox_center[k]) <= 0.5f * w->scene.bbox_size;
            }
            if (!in_box) {
                break; // escapes, as in the simulation
            }
            if (maps_s >= 0.0f || exact_s >= 0.0f) {
                if (++after_first > 3) {
                    break;
                }
            }
            memcpy(p, q, sizeof p);
        }
        if (maps_s >= 0.0f && exact_s >= 0.0f) {
            float dx = maps_point[0] - exact_point[0], dy = maps_point[1] - exact_point[1],
                  dz = maps_point[2] - exact_point[2];
            a->error_texels[a->both++] = sqrt((double)(dx * dx + dy * dy + dz * dz)) / texel;
        } else if (exact_s >= 0.0f) {
            a->missed++;
            bool recorded = false;
            for (int t = 1; t <= 10 && !recorded; ++t) {
                float beyond[3];
                for (int k = 0; k < 3; ++k) {
                    beyond[k] = exact_point[k] + 0.1f * (float)t * texel * exact_dir[k];
                }
                recorded = wx_collider_point_collides(&w->collider, beyond);
            }
            if (recorded) {
                a->missed_recorded_slow += step_texels < 50.0f;
                a->missed_recorded_fast += step_texels >= 50.0f;
            }
            if (getenv("WX_BENCH_EMBREE_DEBUG") != NULL) {
                fprintf(stderr, "missed: exact hit (%g %g %g) at step %g, %.1f texels/step%s\n",
                        exact_point[0], exact_point[1], exact_point[2], exact_s, step_texels,
                        recorded ? ", recorded in a map" : "");
            }
        } else if (maps_s >= 0.0f) {
            a->phantom++;
            a->phantom_below += maps_point[1] < lo[1];
            if (getenv("WX_BENCH_EMBREE_DEBUG") != NULL) {
                fprintf(stderr, "phantom: collider hit (%g %g %g) at step %g\n", maps_point[0],
                        maps_point[1], maps_point[2], maps_s);
            }
        } else {
            a->neither++;
        }
        if (step_texels > a->max_speed_texels) {
            a->max_speed_texels = step_texels;
        }
    }
    return true;
}

static double percentile(double *sorted, int64_t n, double q)
{
    if (n == 0) {
        return NAN;
    }
    int64_t k = (int64_t)ceil(q * (double)n) - 1;
    return sorted[k < 0 ? 0 : k >= n ? n - 1 : k];
}

static bool report_accuracy(const char *name, const maps_world *w, const exact *e,
                            const float lo[3], const float hi[3], int n)
{
    accuracy a;
    if (!measure_accuracy(w, e, lo, hi, n, &a)) {
        return false;
    }
    qsort(a.error_texels, (size_t)a.both, sizeof(double), bench_compare_double);
    double med = percentile(a.error_texels, a.both, 0.5);
    double p95 = percentile(a.error_texels, a.both, 0.95);
    double p99 = percentile(a.error_texels, a.both, 0.99);
    int64_t hits = a.both + a.missed + a.phantom;
    double missed = hits > 0 ? 100.0 * (double)a.missed / (double)hits : 0.0;
    double phantom = hits > 0 ? 100.0 * (double)a.phantom / (double)hits : 0.0;
    double below = hits > 0 ? 100.0 * (double)a.phantom_below / (double)hits : 0.0;
    printf("%-11s %9lld %5d %6lld %7.3f %7.3f %7.3f %8.3f%% %8.3f%% %8.3f%% %9lld %9lld\n",
           name, (long long)e->triangles, w->count, (long long)hits, med, p95, p99, missed,
           phantom, below, (long long)a.missed_recorded_slow, (long long)a.missed_recorded_fast);
    fflush(stdout);
    bench_row("embree", "hit error median (texels)", med, "texels", "<= 0.5", med <= 0.5,
              "%s %d particles", name, n);
    bench_row("embree", "hit error 95th (texels)", p95, "texels", NULL, false, "%s %d particles",
              name, n);
    bench_row("embree", "hit error 99th (texels)", p99, "texels", NULL, false, "%s %d particles",
              name, n);
    bench_row("embree", "missed collisions (%)", missed, "%", NULL, false, "%s %d particles",
              name, n);
    bench_row("embree", "tunnelled under 50 texels/step", (double)a.missed_recorded_slow,
              "particles", "0", a.missed_recorded_slow == 0, "%s %d particles", name, n);
    bench_row("embree", "tunnelled at 50+ texels/step", (double)a.missed_recorded_fast,
              "particles", NULL, false, "%s %d particles", name, n);
    bench_row("embree", "phantom collisions (%)", phantom, "%", NULL, false, "%s %d particles",
              name, n);
    bench_row("embree", "phantom below the geometry (%)", below, "%", NULL, false,
              "%s %d particles", name, n);
    free(a.error_texels);
    return true;
}

// --- (b) speed ----------------------------------------------------------------

typedef struct segments {
    int64_t n;
    float *x0, *y0, *z0, *x1, *y1, *z1;
} segments;

typedef struct speed_job {
    const maps_world *w;
    const exact *e;
    const segments *segs;
    int64_t begin, end;
    bool use_exact;
    int64_t hits;
    int64_t swept; ///< segments the coarse test left to the swept test
} speed_job;

static void *speed_worker(void *arg)
{
    speed_job *j = arg;
    const segments *g = j->segs;
    int64_t hits = 0, swept = 0;
    if (j->use_exact) {
        for (int64_t i = j->begin; i < j->end; ++i) {
            float p0[3] = { g->x0[i], g->y0[i], g->z0[i] }, p1[3] = { g->x1[i], g->y1[i], g->z1[i] };
            float s;
            hits += exact_hit(j->e, p0, p1, &s);
        }
    } else {
        // As the simulator does: the coarse test on blocks of 16, then the swept
        // test on what it left, with the maps' lines prefetched a few ahead.
        enum { B = WX_PARTICLE_BLOCK, CHUNK = 1024, AHEAD = 8 };
        const wx_collider *c = &j->w->collider;
        int64_t cand[CHUNK];
        for (int64_t base = j->begin; base < j->end; base += CHUNK) {
            int64_t stop = base + CHUNK < j->end ? base + CHUNK : j->end;
            int m = 0;
            for (int64_t b = base; b + B <= stop; b += B) {
                uint32_t outside;
                uint32_t clear = wx_collider_coarse_block(c, j->w->cam_list, j->w->count, NULL,
                                                          g->x0 + b, g->y0 + b, g->z0 + b,
                                                          g->x1 + b, g->y1 + b, g->z1 + b,
                                                          &outside);
                uint32_t todo = ~(clear | outside) & 0xFFFFu;
                while (todo != 0) {
                    int k = __builtin_ctz(todo);
                    todo &= todo - 1;
                    cand[m++] = b + k;
                }
            }
            for (int q = 0; q < m; ++q) {
                if (q + AHEAD < m) {
                    int64_t a = cand[q + AHEAD];
                    const float pa[3] = { g->x1[a], g->y1[a], g->z1[a] };
                    wx_collider_prefetch(c, pa);
                }
                int64_t i = cand[q];
                float p0[3] = { g->x0[i], g->y0[i], g->z0[i] };
                float p1[3] = { g->x1[i], g->y1[i], g->z1[i] };
                wx_hit hit;
                hits += wx_collider_sweep(c, p0, p1, &hit);
            }
            swept += m;
        }
    }
    j->hits = hits;
    j->swept = swept;
    return NULL;
}

// Segments per second on THREADS threads.
static double time_segments(const maps_world *w, const exact *e, const segments *g, bool use_exact,
                            int64_t *hits, int64_t *swept)
{
    pthread_t threads[THREADS];
    speed_job jobs[THREADS];
    int64_t chunk = (g->n / THREADS + WX_PARTICLE_BLOCK - 1) / WX_PARTICLE_BLOCK * WX_PARTICLE_BLOCK;
    double t0 = bench_now_s();
    for (int t = 0; t < THREADS; ++t) {
        jobs[t] = (speed_job){ w, e, g, t * chunk, t + 1 == THREADS ? g->n : (t + 1) * chunk,
                               use_exact, 0, 0 };
        if (pthread_create(&threads[t], NULL, speed_worker, &jobs[t]) != 0) {
            speed_worker(&jobs[t]);
            threads[t] = 0;
        }
    }
    *hits = 0;
    *swept = 0;
    for (int t = 0; t < THREADS; ++t) {
        if (threads[t] != 0) {
            pthread_join(threads[t], NULL);
        }
        *hits += jobs[t].hits;
        *swept += jobs[t].swept;
    }
    return (double)g->n / (bench_now_s() - t0);
}

// A UV sphere of radius 1 (as bench_bake writes it), binary PLY with normals.
static bool write_sphere_ply(const char *path, int stacks, int slices)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL) {
        return false;
    }
    fprintf(f,
            "ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property float nx\nproperty float ny\nproperty float nz\n"
            "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
            (stacks + 1) * (slices + 1), stacks * slices * 2);
    for (int i = 0; i <= stacks; ++i) {
        double theta = PI * i / stacks;
        for (int j = 0; j <= slices; ++j) {
            double phi = 2.0 * PI * j / slices;
            float p[6] = { (float)(sin(theta) * cos(phi)), (float)cos(theta),
                           (float)(sin(theta) * sin(phi)) };
            p[3] = p[0];
            p[4] = p[1];
            p[5] = p[2];
            fwrite(p, sizeof p, 1, f);
        }
    }
    for (int i = 0; i < stacks; ++i) {
        for (int j = 0; j < slices; ++j) {
            int32_t a = i * (slices + 1) + j, b = a + 1, c = a + slices + 1, d = c + 1;
            unsigned char three = 3;
            int32_t t1[3] = { a, c, b }, t2[3] = { b, c, d };
            fwrite(&three, 1, 1, f);
            fwrite(t1, sizeof t1, 1, f);
            fwrite(&three, 1, 1, f);
            fwrite(t2, sizeof t2, 1, f);
        }
    }
    return fclose(f) == 0;
}

static bool write_sphere_scene(const char *path, const char *mesh)
{
    FILE *f = fopen(path, "w");
    if (f == NULL) {
        return false;
    }
    fprintf(f,
            "<Weathering>\n"
            "  <Solver><BoundingBox size=\"4\"/><Simulation timeStep=\"0.01\"/></Solver>\n"
            "  <ForceFields><Gravity acceleration=\"9.8\"/></ForceFields>\n"
            "  <Collider><ProjectedMaps>\n"
            "    <Ortho cameraName=\"front\"><View eye=\"0 0 5\" target=\"0 0 0\" up=\"0 1 0\""
            " width=\"2.2\" height=\"2.2\" resolution=\"1024\"/></Ortho>\n"
            "    <Ortho cameraName=\"side\"><View eye=\"5 0.5 0\" target=\"0 0 0\" up=\"0 1 0\""
            " width=\"2.2\" height=\"2.2\" resolution=\"1024\"/></Ortho>\n"
            "    <Ortho cameraName=\"top\"><View eye=\"0 5 0\" target=\"0 0 0\" up=\"0 0 -1\""
            " width=\"2.2\" height=\"2.2\" resolution=\"1024\"/></Ortho>\n"
            "  </ProjectedMaps></Collider>\n"
            "  <Geometry><Mesh file=\"%s\"><Surface material=\"*\" absorption=\"0.2\""
            " bounce=\"0.3\"/></Mesh></Geometry>\n"
            "</Weathering>\n",
            mesh);
    return fclose(f) == 0;
}

// Steps `length` long: starts uniform in the cube around the sphere, outside it
// and where the collider puts no particle (outside its collision set: a
// simulated particle is always put back there), falling steeply.
static bool make_segments(segments *g, int64_t n, float length, const wx_collider *collider)
{
    g->n = n;
    float **arrays[6] = { &g->x0, &g->y0, &g->z0, &g->x1, &g->y1, &g->z1 };
    for (int a = 0; a < 6; ++a) {
        *arrays[a] = malloc((size_t)n * sizeof(float));
        if (*arrays[a] == NULL) {
            return false;
        }
    }
    uint64_t state = 11;
    for (int64_t i = 0; i < n;) {
        float p[3] = { 2.2f * uniform(&state) - 1.1f, 2.2f * uniform(&state) - 1.1f,
                       2.2f * uniform(&state) - 1.1f };
        if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 1.0f ||
            wx_collider_point_collides(collider, p)) {
            continue;
        }
        float d[3] = { uniform(&state) - 0.5f, -2.0f, uniform(&state) - 0.5f };
        float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        float step = length / len;
        g->x0[i] = p[0];
        g->y0[i] = p[1];
        g->z0[i] = p[2];
        g->x1[i] = p[0] + step * d[0];
        g->y1[i] = p[1] + step * d[1];
        g->z1[i] = p[2] + step * d[2];
        ++i;
    }
    return true;
}

static void free_segments(segments *g)
{
    free(g->x0);
    free(g->y0);
    free(g->z0);
    free(g->x1);
    free(g->y1);
    free(g->z1);
}

static double rss_mb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, resident = 0;
    if (f == NULL) {
        return 0.0;
    }
    if (fscanf(f, "%ld %ld", &pages, &resident) != 2) {
        resident = 0;
    }
    fclose(f);
    return (double)resident * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0);
}

static bool speed_for_sphere(const char *dir, int stacks, int slices, segments *gs,
                             const char *const *labels, const float *lengths, int workloads,
                             int64_t count)
{
    char mesh[1200], scene[1200], out[1200];
    snprintf(mesh, sizeof mesh, "%s/sphere_%d.ply", dir, stacks);
    snprintf(scene, sizeof scene, "%s/sphere_%d.xml", dir, stacks);
    snprintf(out, sizeof out, "%s/sphere_%d_out", dir, stacks);
    char mesh_name[64];
    snprintf(mesh_name, sizeof mesh_name, "sphere_%d.ply", stacks);
    if (!write_sphere_ply(mesh, stacks, slices) || !write_sphere_scene(scene, mesh_name)) {
        fprintf(stderr, "bench_embree: cannot write %s\n", mesh);
        return false;
    }
    maps_world w;
    if (!maps_world_load(&w, scene, out, 0)) {
        maps_world_free(&w);
        return false;
    }
    // Embree: the same mesh file through the same importer.
    wx_mesh_data m;
    wx_error err;
    if (wx_mesh_import(mesh, &m, &err) != WX_OK) {
        fprintf(stderr, "bench_embree: %s\n", err.message);
        maps_world_free(&w);
        return false;
    }
    double rss0 = rss_mb();
    exact e;
    double t0 = bench_now_s();
    bool ok = exact_init(&e) &&
              exact_add(&e, m.positions, m.origin, m.vertex_count, m.indices, m.triangle_count);
    if (ok) {
        exact_commit(&e);
    }
    double build_s = bench_now_s() - t0;
    double bvh_mb = rss_mb() - rss0;
    wx_mesh_data_free(&m);
    if (!ok) {
        fprintf(stderr, "bench_embree: Embree could not take the mesh\n");
        exact_free(&e);
        maps_world_free(&w);
        return false;
    }
    double maps_mb = 0.0;
    for (int c = 0; c < w.count; ++c) {
        // What the collider reads: its depth copy and pyramid, normal and impact.
        maps_mb += (double)w.maps[c].width * w.maps[c].height * (4 + 12 + 8) * 1.07 / 1048576.0;
    }
    long long tri = (long long)e.triangles;
    for (int k = 0; k < workloads; ++k) {
        const segments *g = &gs[k];
        if (g->n == 0 && !make_segments(&gs[k], count, lengths[k], &w.collider)) {
            fprintf(stderr, "bench_embree: out of memory\n");
            exact_free(&e);
            maps_world_free(&w);
            return false;
        }
        double ours[3], theirs[3];
        int64_t hits_ours = 0, hits_exact = 0, swept = 0, unused;
        for (int r = 0; r < 3; ++r) {
            ours[r] = time_segments(&w, &e, g, false, &hits_ours, &swept);
            theirs[r] = time_segments(&w, &e, g, true, &hits_exact, &unused);
        }
        double o = bench_median(ours, 3), t = bench_median(theirs, 3);
        printf("%9lld %-10s %10.1f %11.1f %7.2fx %11.3f %7.0f %8.0f %7.2f%% %7.2f%% %7.2f%%\n",
               tri, labels[k], o / 1e6, t / 1e6, o / t, build_s, bvh_mb, maps_mb,
               100.0 * (double)swept / (double)g->n, 100.0 * (double)hits_ours / (double)g->n,
               100.0 * (double)hits_exact / (double)g->n);
        fflush(stdout);
        bench_row("embree", "ours M segments/s", o / 1e6, "M/s", NULL, false,
                  "%lldk tri %s 3 cams 1024 px 2 thr", tri / 1000, labels[k]);
        bench_row("embree", "Embree M segments/s", t / 1e6, "M/s", NULL, false,
                  "%lldk tri %s 2 thr", tri / 1000, labels[k]);
        bench_row("embree", "speed ratio ours/Embree", o / t, "x", NULL, false, "%lldk tri %s",
                  tri / 1000, labels[k]);
    }
    bench_row("embree", "Embree BVH build (s)", build_s, "s", NULL, false, "%lldk triangles",
              tri / 1000);
    bench_row("embree", "Embree BVH memory (MB)", bvh_mb, "MB", NULL, false, "%lldk triangles",
              tri / 1000);
    bench_row("embree", "collider maps memory (MB)", maps_mb, "MB", NULL, false,
              "%lldk triangles 3 cams 1024 px", tri / 1000);
    exact_free(&e);
    maps_world_free(&w);
    remove(mesh);
    remove(scene);
    return true;
}

// The thesis scene's two boxes (tests/tools/gen_thesis_maps.c).
static bool thesis_exact(exact *e)
{
    const float cube_lo[3] = { -1, 0, -1 }, cube_hi[3] = { 1, 2, 1 };
    const float slab_lo[3] = { -3, -0.2f, -3 }, slab_hi[3] = { 3, 0, 3 };
    if (!exact_init(e) || !exact_add_box(e, cube_lo, cube_hi) ||
        !exact_add_box(e, slab_lo, slab_hi)) {
        return false;
    }
    exact_commit(e);
    return true;
}

static bool accuracy_scene(const char *name, const char *scene_path, const char *out, int n)
{
    maps_world w;
    exact e;
    memset(&e, 0, sizeof e);
    bool ok = maps_world_load(&w, scene_path, out, 0);
    float lo[3], hi[3];
    if (ok && w.scene.mesh_count > 0) {
        ok = exact_init(&e);
        for (int k = 0; k < 3; ++k) {
            lo[k] = INFINITY;
            hi[k] = -INFINITY;
        }
        for (int i = 0; ok && i < w.scene.mesh_count; ++i) {
            wx_mesh_data m;
            wx_error err;
            if (wx_mesh_import(w.scene.meshes[i].path, &m, &err) != WX_OK) {
                fprintf(stderr, "bench_embree: %s\n", err.message);
                ok = false;
                break;
            }
            ok = exact_add(&e, m.positions, m.origin, m.vertex_count, m.indices,
                           m.triangle_count);
            for (int k = 0; k < 3; ++k) {
                lo[k] = fminf(lo[k], (float)m.bounds_min[k]);
                hi[k] = fmaxf(hi[k], (float)m.bounds_max[k]);
            }
            wx_mesh_data_free(&m);
        }
        if (ok) {
            exact_commit(&e);
        }
    } else if (ok) {
        ok = thesis_exact(&e);
        const float tlo[3] = { -3, -0.2f, -3 }, thi[3] = { 3, 2, 3 };
        memcpy(lo, tlo, sizeof lo);
        memcpy(hi, thi, sizeof hi);
    }
    if (ok) {
        ok = report_accuracy(name, &w, &e, lo, hi, n);
    }
    exact_free(&e);
    maps_world_free(&w);
    return ok;
}

// --- (c) where the rain lands, per surface --------------------------------------

// The outward facing of a triangle's plane (its vertex normals' side), as one of
// +x -x +y -y +z -z: the axis of its largest component.
static int facing_of(const float n[3])
{
    int axis = 0;
    for (int k = 1; k < 3; ++k) {
        axis = fabsf(n[k]) > fabsf(n[axis]) ? k : axis;
    }
    return 2 * axis + (n[axis] < 0.0f);
}

static void triangle_normal(const wx_mesh_data *m, uint32_t t, float n[3])
{
    const uint32_t *v = &m->indices[3 * t];
    float e1[3], e2[3], mean[3] = { 0, 0, 0 };
    for (int k = 0; k < 3; ++k) {
        e1[k] = m->positions[3 * v[1] + k] - m->positions[3 * v[0] + k];
        e2[k] = m->positions[3 * v[2] + k] - m->positions[3 * v[0] + k];
        for (int c = 0; c < 3; ++c) {
            mean[k] += m->normals[3 * v[c] + k];
        }
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    if (n[0] * mean[0] + n[1] * mean[1] + n[2] * mean[2] < 0.0f) {
        for (int k = 0; k < 3; ++k) {
            n[k] = -n[k];
        }
    }
}

// The triangle nearest a point the collider gives (its primID) and its
// distance: short rays along the six axes from the point (each starting 2
// texels back); -1 when none lies within 4 texels.
static int64_t triangle_at(const exact *e, const float point[3], float texel, float *distance)
{
    int64_t best = -1;
    *distance = INFINITY;
    for (int dir = 0; dir < 6; ++dir) {
        float d[3] = { 0, 0, 0 };
        d[dir / 2] = dir % 2 == 0 ? 1.0f : -1.0f;
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        struct RTCRayHit rh;
        memset(&rh, 0, sizeof rh);
        rh.ray.org_x = point[0] - 2.0f * texel * d[0];
        rh.ray.org_y = point[1] - 2.0f * texel * d[1];
        rh.ray.org_z = point[2] - 2.0f * texel * d[2];
        rh.ray.dir_x = d[0];
        rh.ray.dir_y = d[1];
        rh.ray.dir_z = d[2];
        rh.ray.tfar = 6.0f * texel;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(e->scene, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID &&
            fabsf(rh.ray.tfar - 2.0f * texel) < *distance) {
            *distance = fabsf(rh.ray.tfar - 2.0f * texel);
            best = (int64_t)rh.hit.primID;
        }
    }
    return best;
}

// docs/performance.md, "(c) Where the rain lands": the shipped house's rain
// (its box emitter as it is, without the wind and the turbulence), every drop
// absorbed where it first lands; the collider's and Embree's first hits on the
// same step segments, counted per surface (material and facing).
static bool rain_per_surface(const char *out, int n, int layers)
{
    maps_world w;
    exact e;
    memset(&e, 0, sizeof e);
    wx_mesh_data m;
    memset(&m, 0, sizeof m);
    wx_error err;
    bool ok = maps_world_load(&w, "xml_scenes/building.xml", out, layers) && exact_init(&e);
    if (ok && (wx_mesh_import(w.scene.meshes[0].path, &m, &err) != WX_OK)) {
        fprintf(stderr, "bench_embree: %s\n", err.message);
        ok = false;
    }
    ok = ok && exact_add(&e, m.positions, m.origin, m.vertex_count, m.indices, m.triangle_count);
    if (!ok || w.scene.emitter_count < 1 || m.material_count > 64) {
        exact_free(&e);
        maps_world_free(&w);
        wx_mesh_data_free(&m);
        return false;
    }
    exact_commit(&e);
    enum { FACINGS = 6 };
    int64_t counts[64][FACINGS][2];
    memset(counts, 0, sizeof counts);
    int64_t unattributed = 0, exact_total = 0, maps_total = 0, misrecorded = 0;
    const wx_emitter *em = &w.scene.emitters[0];
    float dt = (float)w.scene.time_step, texel = w.texel_ws;
    for (int i = 0; i < n; ++i) {
        float p[3], v[3], q[3];
        wx_emitter_sample(em, w.scene.seed, wx_particle_id(0, (uint64_t)i), p, v);
        int64_t found[2] = { -1, -1 };
        bool done[2] = { false, false };
        float exact_point[3] = { 0, 0, 0 };
        wx_hit hit_last, ours_hit;
        memset(&hit_last, 0, sizeof hit_last);
        memset(&ours_hit, 0, sizeof ours_hit);
        bool ours_kept = false;
        for (int step = 0; step < w.scene.steps && !(done[0] && done[1]); ++step) {
            for (int k = 0; k < 3; ++k) {
                v[k] += dt * w.forces.gravity[k]; // mass 1; no wind, no turbulence
                q[k] = p[k] + dt * v[k];
            }
            wx_hit hit;
            float s;
            if (!done[0] && maps_hit(&w, p, q, &hit)) {
                done[0] = true;
                hit_last = hit;
                float distance;
                found[0] = triangle_at(&e, hit.point, texel, &distance);
                maps_total++;
                unattributed += found[0] < 0;
                if (found[0] >= 0) {
                    // The normal the simulation reacts with and the texel it
                    // deposits into against the face the point lies on.
                    float tn[3];
                    triangle_normal(&m, (uint32_t)found[0], tn);
                    float tl = sqrtf(tn[0] * tn[0] + tn[1] * tn[1] + tn[2] * tn[2]);
                    float agree = (tn[0] * hit.normal[0] + tn[1] * hit.normal[1] +
                                   tn[2] * hit.normal[2]) / tl;
                    if (agree < 0.7f) {
                        misrecorded++;
                        if (getenv("WX_BENCH_EMBREE_DEBUG") != NULL) {
                            fprintf(stderr, "recorded on another face: camera %d point (%g %g %g) "
                                    "normal (%g %g %g), the face's (%g %g %g)\n", hit.camera,
                                    hit.point[0], hit.point[1], hit.point[2], hit.normal[0],
                                    hit.normal[1], hit.normal[2], tn[0] / tl, tn[1] / tl, tn[2] / tl);
                        }
                    }
                }
            }
            if (!done[1] && exact_hit_triangle(&e, p, q, &s, &found[1])) {
                done[1] = true;
                exact_total++;
                for (int k = 0; k < 3; ++k) {
                    exact_point[k] = p[k] + s * (q[k] - p[k]);
                }
            }
            if (done[0] && !ours_kept) {
                ours_kept = true;
                ours_hit = hit_last;
            }
            bool in_box = true;
            for (int k = 0; k < 3; ++k) {
                in_box = in_box && fabsf(q[k] - w.scene.bbox_center[k]) <= 0.5f * w.scene.bbox_size;
            }
            if (!in_box) {
                break;
            }
            memcpy(p, q, sizeof p);
        }
        if (getenv("WX_BENCH_EMBREE_DEBUG") != NULL && found[1] >= 0 &&
            strcmp(m.material_names[m.materials[found[1]]], "sill") == 0) {
            float tn[3];
            triangle_normal(&m, (uint32_t)found[1], tn);
            bool ours_same = found[0] >= 0 && m.materials[found[0]] == m.materials[found[1]];
            if (facing_of(tn) == 2 && !ours_same) {
                fprintf(stderr,
                        "sill top miss: exact (%.4f %.4f %.4f) ours cam %d layer %d (%.4f %.4f "
                        "%.4f) n (%.2f %.2f %.2f) tri %s\n",
                        exact_point[0], exact_point[1], exact_point[2], ours_hit.camera,
                        ours_hit.layer, ours_hit.point[0], ours_hit.point[1], ours_hit.point[2],
                        ours_hit.normal[0], ours_hit.normal[1], ours_hit.normal[2],
                        found[0] >= 0 ? m.material_names[m.materials[found[0]]] : "none");
            }
        }
        for (int side = 0; side < 2; ++side) {
            if (found[side] >= 0) {
                float tn[3];
                triangle_normal(&m, (uint32_t)found[side], tn);
                counts[m.materials[found[side]]][facing_of(tn)][side]++;
            }
        }
    }
    static const char *const facing_names[FACINGS] = { "+x", "-x", "+y", "-y", "+z", "-z" };
    printf("%-10s %-6s %9s %9s %8s %8s\n", "material", "facing", "Embree", "ours", "ratio",
           "3 sigma");
    double worst = 0.0;
    int surfaces = 0;
    for (int mat = 0; mat < m.material_count; ++mat) {
        for (int f = 0; f < FACINGS; ++f) {
            int64_t ex = counts[mat][f][1], ours = counts[mat][f][0];
            if (ex == 0 && ours == 0) {
                continue;
            }
            double ratio = ex > 0 ? (double)ours / (double)ex : INFINITY;
            printf("%-10s %-6s %9lld %9lld %8.3f %8.3f\n", m.material_names[mat],
                   facing_names[f], (long long)ex, (long long)ours, ratio,
                   ex > 0 ? 3.0 / sqrt((double)ex) : 0.0);
            if (ex >= 100) {
                worst = fmax(worst, fabs(ratio - 1.0));
                surfaces++;
            }
        }
    }
    printf("drops %d: Embree hit %lld, the collider %lld (%lld of its hits on no triangle "
           "within 4 texels; %lld recorded with a normal more than 45 degrees off the face's)\n",
           n, (long long)exact_total, (long long)maps_total, (long long)unattributed,
           (long long)misrecorded);
    char what[96];
    snprintf(what, sizeof what, "rain recorded on another face, %d layer%s", layers,
             layers > 1 ? "s" : "");
    bench_row("embree", what, 100.0 * (double)misrecorded /
              (double)(maps_total > 0 ? maps_total : 1), "% of hits", NULL, false,
              "building.xml rain without wind; %d drops", n);
    snprintf(what, sizeof what, "rain per surface: worst |ours/Embree - 1|, %d layer%s", layers,
             layers > 1 ? "s" : "");
    bench_row("embree", what, 100.0 * worst, "%", "<= 5", worst <= 0.05,
              "building.xml rain without wind; %d drops; %d surfaces with 100 exact hits or more",
              n, surfaces);
    exact_free(&e);
    maps_world_free(&w);
    wx_mesh_data_free(&m);
    return true;
}

int main(void)
{
    const char *build = getenv("WX_BUILD") != NULL ? getenv("WX_BUILD") : "build";
    long n = bench_env_long("WX_BENCH_EMBREE_PARTICLES", 20000);
    long segs = bench_env_long("WX_BENCH_SEGMENTS", 1000000);
    char dir[1024], out[1100];
    snprintf(dir, sizeof dir, "%s/tmp", build);
    mkdir(dir, 0777);
    snprintf(dir, sizeof dir, "%s/tmp/bench_embree", build);
    mkdir(dir, 0777);

    printf("embree (a): depth-map collider against the exact mesh (Embree 3 rtcIntersect1), "
           "%ld particles per scene, 0.5-80 texels per step\n",
           n);
    printf("hit error in texels of the hit camera; missed and phantom in %% of the particles "
           "that hit anything; tunnel = missed where a map records the surface\n");
    printf("%-11s %9s %5s %6s %7s %7s %7s %9s %9s %9s %9s %9s\n", "scene", "triangles", "cams",
           "hits", "median", "95th", "99th", "missed", "phantom", "(below)", "tunnel<50",
           "tunnel50+");
    snprintf(out, sizeof out, "%s/building", dir);
    if (!accuracy_scene("building", "xml_scenes/building.xml", out, (int)n)) {
        return 1;
    }
    snprintf(out, sizeof out, "%s/thesis_box", dir);
    if (!accuracy_scene("thesis_box", "xml_scenes/thesis_box.xml", out, (int)n)) {
        return 1;
    }

    long drops = bench_env_long("WX_BENCH_RAIN_DROPS", 10000);
    printf("embree (c): where the shipped house's rain lands (no wind, no turbulence, every "
           "drop absorbed at its first hit), %ld drops\n",
           drops);
    // With the shipped cameras as they are, then with 4 layers each (docs/design.md
    // section 14): what the layers change in where hits are recorded.
    for (int layers = 1; layers <= 4; layers += 3) {
        snprintf(out, sizeof out, "%s/rain%d", dir, layers);
        printf("%d layer%s:\n", layers, layers > 1 ? "s" : "");
        if (!rain_per_surface(out, (int)drops, layers)) {
            return 1;
        }
    }

    printf("embree (b): %ld segments around a UV sphere in a 2.2 m frame (1024 px: 2.1 mm "
           "texels), %d threads, median of 3\n",
           segs, THREADS);
    printf("%9s %-10s %10s %11s %8s %11s %7s %8s %8s %8s %8s\n", "triangles", "segments",
           "ours M/s", "Embree M/s", "ratio", "BVH build s", "BVH MB", "maps MB", "swept",
           "ours hit", "mesh hit");
    enum { WORKLOADS = 2 };
    static const char *const labels[WORKLOADS] = { "10 texels", "1.5 texels" };
    static const float lengths[WORKLOADS] = { 0.022f, 0.0032f };
    segments g[WORKLOADS];
    memset(g, 0, sizeof g);
    bool made = true;
    static const int sizes[3][2] = { { 50, 100 }, { 158, 316 }, { 500, 1000 } };
    for (int s = 0; made && s < 3; ++s) {
        made = speed_for_sphere(dir, sizes[s][0], sizes[s][1], g, labels, lengths, WORKLOADS,
                                segs);
    }
    for (int k = 0; k < WORKLOADS; ++k) {
        free_segments(&g[k]);
    }
    if (!made) {
        fprintf(stderr, "bench_embree: the speed comparison could not run\n");
        return 1;
    }
    bench_row("embree", "peak RSS", bench_peak_mb(), "MB", NULL, false, "whole benchmark");
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_embree: could not remove %s\n", dir);
    }
    return 0;
}
