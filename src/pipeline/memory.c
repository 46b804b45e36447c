// memory.c: the memory a run needs, what is available, and the refusal of a run
// that would not fit (memory.h, docs/reliability.md).
#include "pipeline/memory.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "model/maps.h"
#include "model/mesh.h"
#include "pipeline/masks_phase.h"
#include "pipeline/outputs.h"
#include "pipeline/texture_phase.h"
#include "sim/emitter.h"
#include "sim/noise.h"

// ---------------------------------------------------------------------------
// Particles alive at once (docs/reliability.md, "Particles alive at once")

// The longest a free flight can last: a particle whose height above the
// solver box's floor is at most h, whose upward speed is at most w, and whose
// upward acceleration is at most -alpha (alpha > 0) leaves the box below
// within this time. With the semi-implicit Euler step (v += dt a; x += dt v)
// after n steps y <= y0 + n dt w - alpha dt^2 n (n + 1) / 2, which is below
// the floor once t = n dt passes the root of alpha t^2 / 2 + (alpha dt / 2 - w)
// t - h = 0; one step more for the step in which it happens.
static double flight_bound(double w, double h, double alpha, double dt)
{
    double b = w - 0.5 * alpha * dt;
    return (b + sqrt(b * b + 2.0 * alpha * h)) / alpha + dt;
}

double wx_memory_particle_lifetime(const wx_scene *scene, const wx_emitter *e)
{
    const double dt = scene->time_step;
    const double run = wx_scene_duration(scene) * (scene->iterations > 1 ? scene->iterations : 1);
    const double mass = e->mass > 0.0f ? e->mass : 1.0;
    // Gravity pulls down; wind and turbulence may push up, each turbulence
    // component by at most its strength (force_field.c clamps it).
    double g = 0.0, up = 0.0, turbulence = 0.0;
    double wind[3] = { 0.0, 0.0, 0.0 };
    for (int f = 0; f < scene->field_count; ++f) {
        const wx_field *fd = &scene->fields[f];
        if (fd->kind == WX_FIELD_GRAVITY) {
            g += fd->strength;
        } else if (fd->kind == WX_FIELD_WIND) {
            double len = sqrt((double)fd->dir[0] * fd->dir[0] + (double)fd->dir[1] * fd->dir[1] +
                              (double)fd->dir[2] * fd->dir[2]);
            for (int k = 0; k < 3 && len > 0.0; ++k) {
                wind[k] += fd->strength * fd->dir[k] / len / mass;
            }
        } else {
            turbulence += fabs((double)fd->strength) / mass;
        }
    }
    up = fmax(0.0, wind[1]) + turbulence;
    const double alpha = g - up; // the least downward acceleration
    if (!(alpha > 0.0) || !(dt > 0.0)) {
        return run; // nothing takes a particle out of the box: it may fly to the end
    }
    // Its speed: the constant forces (gravity, wind) keep the energy of a free
    // flight, a collision never raises it (a bounce keeps R of the normal
    // part, a slide F of the tangential part: R, F <= 1) but for adherence's
    // pull (A dt / m into the surface, at right angles to what a slide keeps),
    // and the box bounds the potential: |v|^2 <= speed^2 + 2 |a| diagonal +
    // collisions x pull^2. Turbulence adds at most its strength x sqrt(3) a
    // second, over at most the run.
    const double a = sqrt(wind[0] * wind[0] + (wind[1] - g) * (wind[1] - g) + wind[2] * wind[2]);
    const double H = scene->bbox_size, diagonal = sqrt(3.0) * H;
    const double pull = scene->collider.adherence * dt / mass;
    const double M = e->max_collisions >= 1 ? e->max_collisions : 1;
    const double speed = sqrt((double)e->speed * e->speed + 2.0 * a * diagonal + M * pull * pull) +
                         sqrt(3.0) * turbulence * run;
    // The first flight starts at the emitter, at most this fast upwards.
    double top = e->kind == WX_EMITTER_BOX        ? fmax(e->box_min[1], e->box_max[1])
                 : e->kind == WX_EMITTER_HEMISPHERE ? e->center[1] + e->radius
                                                    : e->center[1];
    double h0 = fmin(H, fmax(0.0, top - (scene->bbox_center[1] - 0.5 * H)));
    double w0 = e->speed;
    if (e->kind == WX_EMITTER_BOX) {
        // The most upward direction of the cone: its axis tilted up by the spread.
        double from_up = acos(fmax(-1.0, fmin(1.0, (double)e->dir[1])));
        w0 = e->speed * cos(fmax(0.0, from_up - e->spread * 3.14159265358979 / 180.0));
    }
    // A particle dies at its maxCollisions-th collision (or earlier); each
    // collision ends a flight, and the next one starts at most
    // max(R, F) x speed + pull upwards.
    double rho = fmax(scene->collider.resilience, scene->collider.friction);
    double w = fmin(speed, rho * speed + pull);
    double life = flight_bound(w0, h0, alpha, dt) + (M - 1.0) * flight_bound(w, H, alpha, dt);
    return fmin(run, life);
}

double wx_memory_particles_alive(const wx_scene *scene, const wx_emitter *e)
{
    const double T = wx_scene_duration(scene);
    const double iterations = scene->iterations > 1 ? scene->iterations : 1;
    // Each iteration emits over [start, min(end, T)] at `rate`.
    double emitting = fmax(0.0, fmin(e->end, T) - e->start);
    double total = iterations * (double)wx_emitter_count_at(e, T);
    if (!(emitting > 0.0) || !(e->rate > 0.0)) {
        return 0.0;
    }
    // A particle alive at time t was emitted within the lifetime L before it:
    // the busiest window of length L holds q whole iterations and a part of
    // one more, so at most q emitting spans and min(L - q T, span) of another.
    double L = wx_memory_particle_lifetime(scene, e);
    double q = T > 0.0 ? floor(L / T) : iterations;
    double seconds = q >= iterations ? iterations * emitting
                                     : q * emitting + fmin(L - q * T, emitting);
    // Counts are floors of rate x time in each span: one more per span.
    double alive = e->rate * seconds + fmin(q + 1.0, iterations);
    return fmin(total, alive);
}

// The memory importing one mesh takes at its peak (docs/reliability.md): the
// file (Assimp reads it whole) and, per triangle, what Assimp's scene, the
// import's joining and its arrays hold; an OBJ's vertices are its faces'
// corners. Without the imported triangles, WX_MESH_BYTES_PER_FILE_BYTE of
// the file.
static double mesh_import_bytes(const char *path, double file_bytes, const wx_mesh_data *data)
{
    if (data == NULL) {
        return WX_MESH_BYTES_PER_FILE_BYTE * file_bytes;
    }
    size_t n = strlen(path);
    bool obj = n >= 4 && strcasecmp(path + n - 4, ".obj") == 0;
    return WX_MESH_BYTES_PER_IMPORTED_FILE_BYTE * file_bytes +
           (obj ? WX_MESH_BYTES_PER_OBJ_TRIANGLE : WX_MESH_BYTES_PER_TRIANGLE) *
               (double)data->triangle_count;
}

void wx_memory_estimate(const wx_scene *scene, unsigned phases, wx_memory_need *need)
{
    wx_memory_estimate_geometry(scene, phases, NULL, need);
}

void wx_memory_estimate_geometry(const wx_scene *scene, unsigned phases,
                                 const wx_geometry *geometry, wx_memory_need *need)
{
    memset(need, 0, sizeof *need);
    need->baseline_bytes = WX_MEMORY_BASELINE;
    need->camera_line = wx_has_path(scene->path) ? 1 : 0;
    // Substances and ageing (docs/design.md section 9): the planes per substance,
    // the rules' baseline and records, the channels of the dirt maps.
    int S = scene->substance_count > 1 ? scene->substance_count : 1;
    need->substances = S;
    double iterations = scene->iterations > 1 ? (double)scene->iterations : 1.0;
    bool surface_rules = wx_scene_has_surface_rules(scene);
    bool rules = scene->rule_count > 0 || surface_rules;
    bool grow = wx_scene_has_grow(scene);
    char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
    double baked_extra = fmax(0.0, (double)wx_dirt_channels(scene, false, names) - 3.0);
    double simulated_extra = fmax(0.0, (double)wx_dirt_channels(scene, true, names) - 5.0);
    const wx_scene_camera *out =
        scene->output_index >= 0 && scene->output_index < scene->camera_count
            ? &scene->cameras[scene->output_index]
            : NULL;

    double largest = -1.0, input_texels = 0.0, largest_input = 0.0, output_texels = 0.0;
    double framebuffer = 0.0, images = 0.0, baked_inputs = 0.0, kept_images = 0.0;
    bool bake = (phases & WX_PHASE_BAKE) && wx_scene_needs_bake(scene);
    double input_image =
        WX_BAKE_INPUT_IMAGE_BYTES_PER_TEXEL + WX_PLANE_BYTES_PER_TEXEL * baked_extra;
    for (int c = 0; c < scene->camera_count; ++c) {
        const wx_scene_camera *sc = &scene->cameras[c];
        double texels = (double)sc->camera.width * (double)sc->camera.height;
        // Every layer of an input camera (docs/design.md section 14) is a map
        // of its own for the bake's images, the simulation and the gather.
        double layers = !sc->is_output && sc->layers > 1 ? (double)sc->layers : 1.0;
        if (sc->is_output) {
            output_texels = texels;
        } else {
            input_texels += layers * texels;
            largest_input = fmax(largest_input, layers * texels);
        }
        if (texels > largest) {
            largest = texels;
            need->camera_line = sc->line;
        }
        if (bake && sc->has_view && !wx_has_path(sc->depth_path)) {
            // Peeling reads the previous layer's depth from a texture, and
            // each pass is read back whole (10 floats a texel, 2 bytes of
            // state) before it is merged into the layers (raster/bake.c).
            framebuffer = fmax(framebuffer, (WX_BAKE_FRAMEBUFFER_BYTES_PER_TEXEL +
                                             (layers > 1.0 ? 8.0 + 42.0 : 0.0)) * texels);
            images = fmax(images, layers * texels *
                                      (sc->is_output ? WX_BAKE_OUTPUT_IMAGE_BYTES_PER_TEXEL
                                                     : input_image));
            baked_inputs += sc->is_output ? 0.0 : layers * texels;
            kept_images += sc->is_output ? 0.0 : layers * texels * input_image;
        }
    }
    if (bake) {
        double largest_file = -1.0;
        for (int m = 0; m < scene->mesh_count; ++m) {
            struct stat st;
            double bytes = stat(scene->meshes[m].path, &st) == 0 ? (double)st.st_size : 0.0;
            const wx_mesh_data *data =
                geometry != NULL && m < geometry->count ? &geometry->meshes[m].data : NULL;
            need->mesh_bytes += mesh_import_bytes(scene->meshes[m].path, bytes, data);
            // Its smooth surface (raster/bake.c): at most WX_SMOOTH_MAX_TRIANGLES,
            // and at most 64 times its triangles (a file holds a triangle per 16
            // bytes at the most, when it was not imported).
            double triangles = data != NULL ? (double)data->triangle_count : bytes / 16.0;
            double smooth = WX_SMOOTH_BYTES_PER_TRIANGLE *
                            fmin(WX_SMOOTH_MAX_TRIANGLES, 64.0 * triangles);
            need->mesh_bytes += smooth;
            need->smooth_bytes += smooth;
            if (bytes > largest_file) {
                largest_file = bytes;
                need->mesh_line = scene->meshes[m].line;
            }
        }
        // Two cameras' images at once (a run that simulates keeps every input
        // camera's for its simulation: pipeline/run.c), the visibility test's
        // depth planes, the readback strip (1 Mi floats), and the meshes as
        // imported and uploaded.
        double held =
            (phases & WX_PHASE_SIMULATE) ? fmax(2.0 * images, images + kept_images) : 2.0 * images;
        need->bake_bytes = WX_BAKE_CONTEXT_BYTES + framebuffer + held +
                           4.0 * (input_texels > baked_inputs ? input_texels : baked_inputs) +
                           4.0 * 1024.0 * 1024.0 + need->mesh_bytes;
    }
    // The mask: the gather's planes per output texel, one plane per substance.
    double gather_out = WX_GATHER_BYTES_PER_OUTPUT_TEXEL + WX_PLANE_BYTES_PER_TEXEL * (S - 1);
    // Derived masks (docs/masks.md): a plane each, and while they are computed
    // the points (a double position and a flag per texel); the collider's copy
    // of every input camera's depth with its pyramid, and zero impact planes.
    if (scene->mask_count > 0) {
        gather_out += WX_PLANE_BYTES_PER_TEXEL * scene->mask_count + 25.0;
    }
    // With layers a TextureMap's gather builds that collider too (the faces it
    // encloses are not seen: wx_masks_unsee_enclosed).
    bool textures = scene->texture_count > 0 && (phases & (WX_PHASE_SIMULATE | WX_PHASE_GATHER));
    double collider =
        scene->mask_count > 0 || (textures && wx_scene_has_layers(scene))
            ? WX_MASK_COLLIDER_BYTES_PER_TEXEL * input_texels + 8.0 * largest_input
            : 0.0;
    // A Noise mask's remap (sim/noise.h): the area sample kept over the run
    // (3 doubles a point, and a weight without meshes), the sorted values
    // while a table is built, and a table per Noise.
    for (int m = 0, first = 1; m < scene->mask_count; ++m) {
        if (scene->masks[m].kind == WX_MASK_NOISE) {
            collider += first * (32.0 + 16.0) * WX_NOISE_SAMPLE_POINTS +
                        8.0 * WX_NOISE_TABLE_SIZE;
            first = 0;
        }
    }
    bool texture_frames = false;
    for (int t = 0; textures && t < scene->texture_count; ++t) {
        const wx_texture_map *tm = &scene->textures[t];
        double texels = (double)tm->width * (double)tm->height;
        // A raster per file (per UDIM tile), all held over the run.
        need->texture_raster_bytes +=
            WX_TEXTURE_RASTER_BYTES_PER_TEXEL * texels * wx_texture_file_count(tm);
        need->texture_write_bytes = fmax(need->texture_write_bytes,
                                         (double)wx_texture_bytes(scene, tm,
                                                                  (int64_t)input_texels) -
                                             WX_TEXTURE_RASTER_BYTES_PER_TEXEL * texels);
        texture_frames = texture_frames || (tm->every > 0 && iterations >= (double)tm->every);
    }
    if (phases & WX_PHASE_SIMULATE) {
        double per_input = WX_SIM_BYTES_PER_INPUT_TEXEL +
                           WX_SIM_BYTES_PER_SUBSTANCE_TEXEL * (S - 1) +
                           (rules ? WX_SIM_BASELINE_BYTES_PER_SUBSTANCE_TEXEL * S : 0.0) +
                           (surface_rules ? WX_PLANE_BYTES_PER_TEXEL : 0.0) +
                           (grow ? WX_PLANE_BYTES_PER_TEXEL : 0.0);
        // The planes taken from the simulation for the gather: amount and
        // baseline per substance, and the hits.
        double planes = WX_PLANE_BYTES_PER_TEXEL * (2.0 * S + 1.0);
        double write =
            (WX_SIM_WRITE_BYTES_PER_TEXEL + WX_PLANE_BYTES_PER_TEXEL * simulated_extra + planes) *
            largest_input;
        // A frame (<OutputMap every="k">) gathers the mask in the middle of the
        // simulation: those planes of every input camera and the gather's own,
        // with the output camera's maps (kept from the bake or read).
        if (out != NULL && out->every > 0 && iterations >= (double)out->every) {
            need->frame_bytes = planes * input_texels + gather_out * output_texels;
        }
        if (texture_frames) {
            need->frame_bytes = fmax(need->frame_bytes, planes * input_texels) +
                                need->texture_write_bytes;
        }
        // With frames, the derived masks' collider lives through the simulation,
        // with a plane per geometric mask at every target (masks_phase.h).
        if (need->frame_bytes > 0.0 && wx_masks_worth_keeping(scene)) {
            double targets = out != NULL ? output_texels : 0.0;
            for (int t = 0; textures && t < scene->texture_count; ++t) {
                targets += (double)scene->textures[t].width * (double)scene->textures[t].height *
                           wx_texture_file_count(&scene->textures[t]);
            }
            int geometric = 0;
            for (int m = 0; m < scene->mask_count; ++m) {
                geometric += wx_mask_is_geometric(scene, m);
            }
            need->frame_bytes += collider + WX_PLANE_BYTES_PER_TEXEL * geometric * targets;
        }
        // Without frames, a run that bakes keeps the output camera's depth and
        // normal through the simulation for its gather.
        double kept = need->frame_bytes == 0.0 && bake && (phases & WX_PHASE_GATHER)
                          ? WX_BAKE_OUTPUT_IMAGE_BYTES_PER_TEXEL * output_texels
                          : 0.0;
        // A run that gathers builds the derived masks' collider before the
        // simulation, which steps through it (pipeline/run.c): the context's
        // own planes (zero impact, noise tables) live through the simulation.
        if (need->frame_bytes == 0.0 && (phases & WX_PHASE_GATHER) && collider > 0.0) {
            kept += collider - WX_MASK_COLLIDER_BYTES_PER_TEXEL * input_texels;
        }
        need->sim_map_bytes = per_input * input_texels + fmax(write, need->frame_bytes) + kept +
                              need->texture_raster_bytes;
        largest = -1.0;
        double duration = wx_scene_duration(scene);
        for (int e = 0; e < scene->emitter_count; ++e) {
            // The emitters emit again in every iteration (docs/design.md
            // section 9); only those alive at once take memory.
            double n = iterations * (double)wx_emitter_count_at(&scene->emitters[e], duration);
            double alive = wx_memory_particles_alive(scene, &scene->emitters[e]);
            need->particles += n;
            need->particles_alive += alive;
            if (alive > largest) {
                largest = alive;
                need->emitter_line = scene->emitters[e].line;
            }
        }
        need->bytes_per_particle = WX_BYTES_PER_PARTICLE + WX_BYTES_PER_PARTICLE_LOAD * (S - 1);
        need->particle_bytes = need->particles_alive * need->bytes_per_particle;
    }
    if (phases & WX_PHASE_GATHER) {
        need->gather_bytes =
            (WX_GATHER_BYTES_PER_INPUT_TEXEL + WX_PLANE_BYTES_PER_TEXEL * simulated_extra) *
                input_texels +
            gather_out * (out != NULL ? output_texels : 0.0) + collider + need->texture_raster_bytes +
            need->texture_write_bytes;
    }
    // The renderer leaves part of its memory behind for the phases after it.
    // What the bake leaves behind: the renderer's caches, and the heap its
    // smooth surfaces took (freed, but still counted in the peak's pages).
    double residue = need->bake_bytes > 0.0 ? WX_BAKE_RESIDUE_BYTES + need->smooth_bytes : 0.0;
    double sim =
        need->sim_map_bytes + need->particle_bytes + ((phases & WX_PHASE_SIMULATE) ? residue : 0.0);
    double gather = need->gather_bytes + ((phases & WX_PHASE_GATHER) ? residue : 0.0);
    double peak = need->bake_bytes;
    need->phase = "bake";
    if (sim > peak) {
        peak = sim;
        need->phase = "simulation";
    }
    if (gather > peak) {
        peak = gather;
        need->phase = "gather";
    }
    need->total_bytes = need->baseline_bytes + WX_MEMORY_MARGIN * peak;
}

// A "Key:   1234 kB" line of /proc/meminfo, in bytes; < 0 when absent.
static double meminfo_bytes(const char *key)
{
    FILE *f = fopen("/proc/meminfo", "r");
    if (f == NULL) {
        return -1.0;
    }
    char line[256];
    double bytes = -1.0;
    size_t key_len = strlen(key);
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, key, key_len) == 0 && line[key_len] == ':') {
            bytes = 1024.0 * strtod(line + key_len + 1, NULL);
            break;
        }
    }
    fclose(f);
    return bytes;
}

// A cgroup v2 number file ("max" or bytes); < 0 when absent or "max".
static double cgroup_number(const char *path)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return -1.0;
    }
    char text[64] = "";
    double value = -1.0;
    if (fgets(text, sizeof text, f) != NULL && text[0] >= '0' && text[0] <= '9') {
        value = strtod(text, NULL);
    }
    fclose(f);
    return value;
}

static void take_min(double *least, double value)
{
    if (value >= 0.0 && (*least < 0.0 || value < *least)) {
        *least = value;
    }
}

double wx_memory_available(void)
{
    const char *override = getenv("WX_MEMORY_AVAILABLE_MB");
    if (override != NULL && override[0] != '\0') {
        char *end = NULL;
        double mb = strtod(override, &end);
        if (end != override && *end == '\0' && mb >= 0.0) {
            return mb * 1024.0 * 1024.0;
        }
    }
    double least = meminfo_bytes("MemAvailable");
    if (least < 0.0) {
        long pages = sysconf(_SC_AVPHYS_PAGES);
        long page = sysconf(_SC_PAGESIZE);
        if (pages > 0 && page > 0) {
            least = (double)pages * (double)page;
        }
    }
    double cg_max = cgroup_number("/sys/fs/cgroup/memory.max");
    double cg_now = cgroup_number("/sys/fs/cgroup/memory.current");
    if (cg_max >= 0.0) {
        take_min(&least, cg_now >= 0.0 && cg_now < cg_max ? cg_max - cg_now : 0.0);
    }
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        take_min(&least, (double)rl.rlim_cur);
    }
    if (getrlimit(RLIMIT_DATA, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY) {
        take_min(&least, (double)rl.rlim_cur);
    }
    return least;
}

static double gib(double bytes)
{
    return bytes / (1024.0 * 1024.0 * 1024.0);
}

wx_result wx_memory_check(const wx_scene *scene, unsigned phases, const wx_geometry *geometry,
                          wx_error *err)
{
    wx_memory_need need;
    wx_memory_estimate_geometry(scene, phases, geometry, &need);
    double available = wx_memory_available();
    if (available < 0.0 || need.total_bytes <= available) {
        return WX_OK;
    }
    if (need.baseline_bytes >= available) {
        return wx_fail(err, WX_CAUSE_MEMORY_LIMIT,
                       "%s: the program itself needs about %.3g GiB before any map or "
                       "particle, but only %.3g GiB of memory is available (see "
                       "docs/reliability.md)",
                       scene->path, gib(need.baseline_bytes), gib(available));
    }
    if (strcmp(need.phase, "simulation") == 0 && need.particle_bytes > need.sim_map_bytes) {
        return wx_fail(err, WX_CAUSE_MEMORY_LIMIT,
                       "%s:%d: the emitters would emit %.4g particles, up to %.4g alive at "
                       "once: with the maps that needs about %.3g GiB (%.0f bytes per "
                       "particle, %.3g GiB of maps), but only %.3g GiB of memory is "
                       "available; lower the rate%s the duration%s (see docs/reliability.md)",
                       scene->path, need.emitter_line, need.particles, need.particles_alive,
                       gib(need.total_bytes),
                       need.bytes_per_particle, gib(need.sim_map_bytes), gib(available),
                       scene->iterations > 1 ? "," : " or",
                       scene->iterations > 1 ? " or the iterations" : "");
    }
    if (strcmp(need.phase, "bake") == 0 && need.mesh_bytes > need.bake_bytes - need.mesh_bytes) {
        return wx_fail(err, WX_CAUSE_MEMORY_LIMIT,
                       "%s:%d: importing and baking the meshes needs about %.3g GiB (%.3g "
                       "GiB to import %.0f MiB of mesh files), but only %.3g GiB of memory "
                       "is available (see docs/reliability.md)",
                       scene->path, need.mesh_line, gib(need.total_bytes), gib(need.mesh_bytes),
                       need.mesh_bytes / WX_MESH_BYTES_PER_FILE_BYTE / (1024.0 * 1024.0),
                       gib(available));
    }
    return wx_fail(err, WX_CAUSE_MEMORY_LIMIT,
                   "%s:%d: the maps need about %.3g GiB at the peak (the %s), but only %.3g "
                   "GiB of memory is available; use smaller maps (see docs/reliability.md)",
                   scene->path, need.camera_line, gib(need.total_bytes), need.phase,
                   gib(available));
}
