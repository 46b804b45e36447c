// info.c: `weathering info SCENE.xml` (docs/design.md section 6): the scene as
// read and checked, what each part will do, and the estimates of a run (its
// particles, rays, coverage, frames, memory and the pilot's share of misses).
#include "cli.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/limits.h"
#include "model/camera.h"
#include "model/geometry.h"
#include "model/scene.h"
#include "pipeline/bake_phase.h"
#include "pipeline/estimate.h"
#include "pipeline/gather_phase.h"
#include "pipeline/masks_phase.h"
#include "pipeline/memory.h"
#include "pipeline/outputs.h"
#include "pipeline/pilot.h"
#include "pipeline/pipeline.h"
#include "pipeline/texture_phase.h"

// --- info ---------------------------------------------------------------------

static const char *field_name(wx_field_kind kind)
{
    switch (kind) {
    case WX_FIELD_GRAVITY: return "Gravity";
    case WX_FIELD_WIND: return "Wind";
    case WX_FIELD_TURBULENCE: return "Turbulence";
    }
    return "?";
}

// The rule as the scene writes it: "Transfer water -> rust 0.2", "Decay water
// 0.5", "Grow moss 2 per m^2", "Spread rust radius 0.02 probability 0.5 where
// water >= 0.2 per m^2".
static void print_rule(const wx_scene *scene, const wx_rule *rule)
{
    const char *name = rule->substance >= 0 && rule->substance < scene->substance_count
                           ? scene->substances[rule->substance]
                           : "?";
    switch (rule->kind) {
    case WX_RULE_TRANSFER:
        printf("Transfer %s -> %s %g", name,
               rule->to >= 0 && rule->to < scene->substance_count ? scene->substances[rule->to]
                                                                  : "?",
               rule->rate);
        break;
    case WX_RULE_DECAY: printf("Decay %s %g", name, rule->rate); break;
    case WX_RULE_GROW: printf("Grow %s %g per m^2", name, rule->amount); break;
    case WX_RULE_SEED:
        printf("Seed %s %g per m^2", name, rule->density);
        break;
    case WX_RULE_SPREAD:
        printf("Spread %s radius %g probability %g", name, rule->radius, rule->probability);
        break;
    case WX_RULE_CRACK:
        printf("Crack %s radius %g strength %g", name, rule->radius, rule->strength);
        break;
    case WX_RULE_PEEL:
        printf("Peel %s from %s radius %g probability %g", name,
               rule->to >= 0 && rule->to < scene->substance_count ? scene->substances[rule->to]
                                                                  : "?",
               rule->radius, rule->probability);
        break;
    }
    if (rule->kind != WX_RULE_TRANSFER && rule->kind != WX_RULE_DECAY &&
        rule->kind != WX_RULE_GROW && rule->where >= 0 && rule->where < scene->substance_count) {
        printf(" where %s >= %g per m^2", scene->substances[rule->where], rule->min);
    }
}

// The rules in document order, separated by commas.
static void print_rules(const wx_scene *scene, const wx_rule *rules, int count)
{
    for (int r = 0; r < count; ++r) {
        printf("%s", r ? ", " : "");
        print_rule(scene, &rules[r]);
    }
}

static int scene_iterations(const wx_scene *scene)
{
    return scene->iterations > 1 ? scene->iterations : 1;
}

// What an image sequence costs (issue 24: info said nothing of 100 000 frames
// at 256 x 256, 1.7 h and 2 GB): its frames, their floats on disk before and
// after ZIP (which left 5-20% on the shipped scenes), and the time of their
// gathers, one a frame, at a rough 400 ns per target texel, input camera and
// substance (measured on 2 cores: 42-72 ms a frame for the thesis box at 256²).
static void print_sequence_cost(const wx_scene *scene, int frames, int channels, int width,
                                int height)
{
    const double ns_per_texel = 400.0, gib = 1024.0 * 1024.0 * 1024.0;
    double texels = (double)width * (double)height;
    double floats = (double)frames * (double)channels * texels * 4.0;
    double frame_s = texels * scene->input_count * scene->substance_count * ns_per_texel * 1e-9;
    double total_s = frame_s * frames;
    // In GiB from half a GiB, else in MiB.
    double unit = floats >= 0.5 * gib ? gib : gib / 1024.0;
    const char *unit_name = floats >= 0.5 * gib ? "GiB" : "MiB";
    char size[96], time[64];
    snprintf(size, sizeof size, "%.3g %s of floats (%.2g-%.2g after ZIP)", floats / unit,
             unit_name, 0.05 * floats / unit, 0.2 * floats / unit);
    if (total_s >= 3600.0) {
        snprintf(time, sizeof time, "%.2g h", total_s / 3600.0);
    } else if (total_s >= 60.0) {
        snprintf(time, sizeof time, "%.2g min", total_s / 60.0);
    } else {
        snprintf(time, sizeof time, "%.2g s", total_s);
    }
    printf("  %-12s        %d frame%s of %d channel%s: %s on disk, about %s of "
           "gathering (%.2g s a frame)%s\n",
           "", frames, frames == 1 ? "" : "s", channels, channels == 1 ? "" : "s", size, time,
           frame_s,
           frames > 1000 ? "; a long sequence: a larger every= writes fewer frames" : "");
}

static void print_camera(const wx_scene *scene, const wx_scene_camera *sc)
{
    const wx_camera *cam = &sc->camera;
    float w_ws, h_ws, dir[3], center[3];
    wx_camera_frame_size(cam, &w_ws, &h_ws);
    wx_camera_view_dir(cam, dir);
    const float uvd[3] = { 0.5f, 0.5f, 0.0f };
    wx_camera_map_to_world(cam, uvd, center);
    printf("  %-12s %-6s %5d x %-5d  frame %g x %g m, eye-plane centre (%g, %g, %g), "
           "looking (%.3g, %.3g, %.3g), texel %.4g m%s\n",
           sc->name, sc->is_output ? "output" : "input", cam->width, cam->height, w_ws, h_ws,
           center[0], center[1], center[2], dir[0], dir[1], dir[2],
           cam->width > 0 ? w_ws / (float)cam->width : 0.0f,
           sc->has_view && !wx_has_path(sc->depth_path) ? ", maps baked from geometry" : "");
    if (sc->is_output && sc->adaptive) {
        float texel = cam->width > 0 ? w_ws / (float)cam->width : 0.0f;
        printf("  %-12s        mask '%s' %d x %d, adaptive smoothing: noise %g%%, radius up to "
               "%g m (%.3g texels)%s\n",
               "", sc->output_file, sc->output_width, sc->output_height, 100.0 * sc->noise,
               sc->max_radius, texel > 0.0f ? sc->max_radius / texel : 0.0,
               sc->normalize ? ", normalised to [0,1]" : "");
    } else if (sc->is_output) {
        printf("  %-12s        mask '%s' %d x %d, radius %g m, %s%s\n", "", sc->output_file,
               sc->output_width, sc->output_height, sc->radius,
               sc->second_pass == WX_SECOND_PASS_SUM ? "thesis sum" : "weighted mean",
               sc->normalize ? ", normalised to [0,1]" : "");
    }
    // The mask's channels (one per substance) and its image sequence.
    if (sc->is_output && (scene->substances_declared || sc->every > 0)) {
        char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
        int channels = wx_mask_channels(scene, names);
        printf("  %-12s        channel%s", "", channels > 1 ? "s" : "");
        for (int c = 0; c < channels; ++c) {
            printf("%s %s", c ? "," : "", names[c]);
        }
        int iterations = scene_iterations(scene);
        int frames = sc->every > 0 ? iterations / sc->every : 0;
        if (frames > 0) {
            char first[WX_OUTPUT_NAME_MAX], last[WX_OUTPUT_NAME_MAX];
            wx_frame_name(sc->output_file, sc->every, first, sizeof first);
            wx_frame_name(sc->output_file, frames * sc->every, last, sizeof last);
            if (frames == 1) {
                printf("; frame '%s' after iteration %d", first, sc->every);
            } else if (sc->every == 1) {
                printf("; frames '%s' to '%s', one after every iteration", first, last);
            } else {
                printf("; frames '%s' to '%s', one after every %d iterations", first, last,
                       sc->every);
            }
        } else if (sc->every > 0) {
            printf("; no frame: every=\"%d\" is more than the %d iteration%s", sc->every,
                   iterations, iterations == 1 ? "" : "s");
        }
        printf("\n");
        if (frames > 0) {
            print_sequence_cost(scene, frames, channels, sc->output_width, sc->output_height);
        }
    }
}

// Whether the cameras frame the mesh: its vertices outside every input
// camera's frame (nothing is known there) and outside the output camera's.
static void print_frames(const wx_scene *scene, const wx_mesh_data *mesh)
{
    int64_t unseen = 0, out_of_shot = 0;
    for (int64_t v = 0; v < mesh->vertex_count && mesh->positions != NULL; ++v) {
        float p[3];
        for (int k = 0; k < 3; ++k) {
            p[k] = (float)(mesh->origin[k] + mesh->positions[3 * v + k]);
        }
        bool seen = false;
        for (int c = 0; c < scene->camera_count; ++c) {
            float uvd[3];
            wx_camera_world_to_map(&scene->cameras[c].camera, p, uvd);
            bool inside = uvd[0] >= 0.0f && uvd[0] <= 1.0f && uvd[1] >= 0.0f && uvd[1] <= 1.0f;
            if (scene->cameras[c].is_output) {
                out_of_shot += !inside;
            } else {
                seen = seen || inside;
            }
        }
        unseen += !seen;
    }
    if (unseen == 0) {
        printf("    every vertex lies inside an input camera's frame");
    } else {
        printf("    %lld of %lld vertices lie outside every input camera's frame (nothing is "
               "known there)",
               (long long)unseen, (long long)mesh->vertex_count);
    }
    if (scene->output_index >= 0) {
        printf(out_of_shot == 0 ? "; all inside the output camera's\n"
                                : "; %lld outside the output camera's\n",
               (long long)out_of_shot);
    } else {
        printf("\n");
    }
}

// The derived masks (docs/masks.md), and what their rays cost: one per point
// of the mask and of every texture, estimated at the texels they cover at most,
// at the rate bench_masks measures (about 1.3 million rays a second a thread).
static void print_masks(const wx_scene *scene, int threads)
{
    static const char *const kinds[] = { "accessibility", "exposure", "curvature",
                                         "height",        "combine",  "noise" };
    if (scene->mask_count == 0) {
        return;
    }
    double points = 0.0;
    double rays = wx_masks_rays(scene, &points);
    printf("masks (%d), channels NAME.Y:\n", scene->mask_count);
    for (int m = 0; m < scene->mask_count; ++m) {
        const wx_mask_def *md = &scene->masks[m];
        printf("  %-12s %s", md->name, kinds[md->kind]);
        switch (md->kind) {
        case WX_MASK_ACCESSIBILITY:
            printf(", %d rays within %g", md->rays, (double)md->distance);
            break;
        case WX_MASK_EXPOSURE:
            printf(", sun at elevation %g azimuth %g", (double)md->elevation, (double)md->azimuth);
            if (md->side_weight != 0.0f) {
                printf(", side suns of weight %g at elevation %g azimuth %g +- %g",
                       (double)md->side_weight, (double)(md->side_elevation * md->elevation),
                       (double)md->azimuth, (double)md->side_spread);
            }
            break;
        case WX_MASK_CURVATURE:
            if (md->radius > 0.0f) {
                printf(", over %g", (double)md->radius);
            } else {
                printf(", over 4 target texels");
            }
            break;
        case WX_MASK_HEIGHT:
            if (md->has_min && md->has_max) {
                printf(", y from %g to %g", (double)md->min, (double)md->max);
            } else {
                printf(", y over the geometry's bounds%s", md->has_min || md->has_max ? " (one end given)" : "");
            }
            break;
        case WX_MASK_NOISE:
            printf(", frequency %g, %d octaves, gain %g, seed %llu, uniform over the area",
                   (double)md->frequency, md->octaves, (double)md->gain,
                   (unsigned long long)md->noise_seed);
            break;
        case WX_MASK_COMBINE:
            printf(", scale %g:", (double)md->scale);
            for (int k = 0; k < md->term_count; ++k) {
                const wx_term *t = &md->terms[k];
                printf(" %s%g x S(", k > 0 ? "+ " : "", (double)t->weight);
                if (t->kind == WX_TERM_CONSTANT) {
                    printf("%g", (double)t->constant);
                } else if (t->kind == WX_TERM_AGE) {
                    printf("%g x age", (double)t->constant);
                } else {
                    printf("%s", t->kind == WX_TERM_MASK ? scene->masks[t->index].name
                                                          : scene->substances[t->index]);
                }
                printf(t->steepness > 0.0f ? "; offset %g, steepness %g)" : ")",
                       (double)t->offset, (double)t->steepness);
            }
            break;
        }
        printf("\n");
    }
    if (rays > 0.0) {
        printf("  rays: at most %.0f million over %.0f target texels, about %.0f s on %d thread%s",
               rays / 1e6, points, rays / (1.3e6 * threads), threads, threads == 1 ? "" : "s");
        // With frames, the masks that read only the geometry are computed once
        // (pipeline/masks_phase.h); a Combine of a substance costs no rays.
        printf(wx_masks_worth_keeping(scene) ? ", once for all the frames\n" : "\n");
    }
}

// A TextureMap: its mesh, size, UV channel and smoothing; its coverage,
// overlaps and padding estimated on a raster of at most 1024 texels a side;
// the triangles outside the tile (exact); its memory.
static void print_texture(const wx_scene *scene, const wx_texture_map *t, const wx_mesh_data *mesh)
{
    printf("texture %s of mesh '%s' (line %d): %d x %d texels over UV channel %d, padding %d",
           t->file, wx_mesh_display_name(scene, &scene->meshes[t->mesh]), t->line, t->width,
           t->height, t->uv, t->padding);
    int frames = t->every > 0 ? scene_iterations(scene) / t->every : 0;
    if (t->every > 0) {
        printf(", a frame every %d iterations (%d frame%s)", t->every, frames,
               frames == 1 ? "" : "s");
    }
    if (!t->adaptive) {
        printf(", smoothing radius %g", (double)t->radius);
    } else if (t->max_radius > 0.0f) {
        printf(", adaptive smoothing (noise %g, maxRadius %g)", (double)t->noise,
               (double)t->max_radius);
    } else {
        printf(", adaptive smoothing (noise %g, maxRadius %g texels of each input camera)",
               (double)t->noise, (double)WX_DEFAULT_MAX_RADIUS_TEXELS);
    }
    printf("%s\n", t->tiles == WX_TILES_UDIM  ? ", one file per UDIM tile (tiles=\"udim\")"
                   : t->tiles == WX_TILES_CLIP ? ", the [0,1] tile only (tiles=\"clip\")"
                                               : "");
    const int files = wx_texture_file_count(t);
    if (t->tiles == WX_TILES_UDIM) {
        char first[WX_OUTPUT_NAME_MAX] = "", last[WX_OUTPUT_NAME_MAX] = "";
        if (files > 0) {
            wx_tile_name(t->file, wx_texture_file_tile(t, 0), first, sizeof first);
            wx_tile_name(t->file, wx_texture_file_tile(t, files - 1), last, sizeof last);
        }
        printf("    UDIM tiles: %d (where a texel centre lies inside a triangle)%s%s%s%s\n", files,
               files > 0 ? ": " : "", first, files > 1 ? (files > 2 ? " ... " : ", ") : "",
               files > 1 ? last : "");
    }
    // On a raster of at most 1024 texels a side (estimate.h).
    for (int f = 0; f < (files > 0 ? files : 1); ++f) {
        wx_texture_coverage r;
        wx_error err;
        int udim = files > 0 ? wx_texture_file_tile(t, f) : 0;
        if (wx_texture_coverage_estimate(t, mesh, udim, &r, &err) != WX_OK) {
            printf("    coverage: not estimated (%s)\n", err.message);
            break;
        }
        const int w = r.width, h = r.height;
        double n = (double)w * (double)h;
        char tile[32] = "";
        if (t->tiles == WX_TILES_UDIM) {
            snprintf(tile, sizeof tile, " of tile %d", WX_UDIM_FIRST + udim);
        }
        if (files > 0 || t->tiles != WX_TILES_UDIM) {
            printf("    coverage%s: about %.1f%% of the texels covered, %.2f%% overlapping, %.1f%% "
                   "padding (on %d x %d)",
                   tile, 100.0 * (double)r.covered / n, 100.0 * (double)r.overlapping / n,
                   100.0 * (double)r.padded / n, w, h);
        }
        if (f == 0) {
            // The triangles (exact, the same for every tile).
            printf("%s%lld of %lld triangles reach outside %s", files > 0 || t->tiles != WX_TILES_UDIM ? "; " : "    ",
                   (long long)r.triangles_outside, (long long)mesh->triangle_count,
                   t->tiles == WX_TILES_UDIM   ? "the UDIM tiles 1001 to 2000 (not written)"
                   : t->tiles == WX_TILES_CLIP ? "the [0,1] tile (not written)"
                                               : "the [0,1] tile (they wrap, as REPEAT reads them)");
            printf("; %lld without usable UVs", (long long)r.triangles_unusable);
        }
        printf("\n");
    }
    int64_t input_texels = 0;
    for (int c = 0; c < scene->camera_count; ++c) {
        if (!scene->cameras[c].is_output) {
            input_texels += (int64_t)scene->cameras[c].camera.width * scene->cameras[c].camera.height;
        }
    }
    printf("    writing it needs about %.0f MiB%s\n",
           (double)wx_texture_bytes(scene, t, input_texels) / (1024.0 * 1024.0),
           files > 1 ? " a tile, one tile at a time" : "");
    if (frames > 0) {
        char names[WX_IMAGE_MAX_CHANNELS][WX_NAME_MAX];
        print_sequence_cost(scene, frames, wx_texture_channels(scene, names), t->width,
                            t->height);
    }
}

int command_info(const cli_args *args)
{
    wx_scene scene;
    wx_run_def opts;
    int status = cli_load_scene(args, &scene, &opts);
    if (status != WX_OK) {
        return status;
    }
    // The gather's limits, the outputs and --stats are checked and the meshes
    // read as a run does, so that info refuses what a run would (but for the
    // memory, which it reports), before it prints anything.
    wx_geometry geometry;
    memset(&geometry, 0, sizeof geometry);
    bool imported = wx_scene_needs_bake(&scene) || scene.texture_count > 0;
    wx_error err;
    wx_result r = wx_gather_check(&scene, &err);
    if (r == WX_OK && imported) {
        r = wx_geometry_load(&scene, args->quiet, &geometry, &err);
    }
    // A tiles="udim" texture's files are its mesh's tiles: known from here on.
    if (r == WX_OK && imported) {
        wx_textures_find_tiles(&scene, &geometry);
    }
    if (r == WX_OK) {
        r = wx_check_outputs(&scene, &opts, WX_PHASE_ALL, &err);
    }
    if (r != WX_OK) {
        fprintf(stderr, "weathering: %s\n", err.message);
        wx_geometry_free(&geometry);
        wx_scene_free(&scene);
        return r;
    }
    printf("scene %s\n", scene.path);
    int iterations = scene_iterations(&scene);
    printf("solver: bounding box %g m centred at (%g, %g, %g); %" PRId64
           " steps of %g s (%g s simulated)",
           scene.bbox_size, scene.bbox_center[0], scene.bbox_center[1], scene.bbox_center[2],
           scene.steps, scene.time_step, wx_scene_duration(&scene));
    if (iterations > 1) {
        printf(" in each of %d iterations (%" PRId64 " steps, %g s in all)", iterations,
               scene.steps * iterations, wx_scene_duration(&scene) * iterations);
    }
    printf("; seed %" PRIu64 "\n", opts.seed);
    // A tile of a larger scene (docs/tiles.md).
    if (scene.tile.present) {
        const wx_tile_def *t = &scene.tile;
        printf("tile: x in [%g, %g), z in [%g, %g), halo %g: the outputs hold only its points, "
               "the particles that start within the halo fly\n",
               t->min[0], t->max[0], t->min[1], t->max[1], t->halo);
    }
    // Substances (docs/design.md section 9): without <Substances> the one "dirt".
    printf("substances (%d):", scene.substance_count);
    for (int k = 0; k < scene.substance_count; ++k) {
        printf("%s %s", k ? "," : "", scene.substances[k]);
    }
    printf("%s\n", scene.substances_declared ? "" : " (default)");
    printf("cameras (%d input, %d output):\n", scene.input_count, scene.output_index >= 0 ? 1 : 0);
    for (int c = 0; c < scene.camera_count; ++c) {
        print_camera(&scene, &scene.cameras[c]);
    }
    printf("emitters (%d):\n", scene.emitter_count);
    for (int e = 0; e < scene.emitter_count; ++e) {
        const wx_emitter *em = &scene.emitters[e];
        // The emitters emit again in every iteration.
        int64_t per_iteration = wx_emitter_particles(&scene, e);
        int64_t count = per_iteration * iterations;
        if (em->kind == WX_EMITTER_BOX) {
            printf("  %-12s %-10s (%g, %g, %g) to (%g, %g, %g), direction (%g, %g, %g)",
                   em->name[0] ? em->name : "(unnamed)", "box", em->box_min[0], em->box_min[1],
                   em->box_min[2], em->box_max[0], em->box_max[1], em->box_max[2], em->dir[0],
                   em->dir[1], em->dir[2]);
            if (em->spread > 0.0f) {
                printf(" within %g degrees", em->spread);
            }
            // The box's shadow on a plane across the flow: with straight parallel
            // paths, count / shadow particles cross each square metre of it.
            double shadow = 0.0;
            for (int k = 0; k < 3; ++k) {
                double a = (double)em->box_max[(k + 1) % 3] - em->box_min[(k + 1) % 3];
                double b = (double)em->box_max[(k + 2) % 3] - em->box_min[(k + 2) % 3];
                shadow += fabs((double)em->dir[k]) * a * b;
            }
            if (shadow > 0.0) {
                printf(" (%.4g particles per square metre across it%s)",
                       (double)per_iteration / shadow, iterations > 1 ? " in each iteration" : "");
            }
        } else {
            printf("  %-12s %-10s at (%g, %g, %g)", em->name[0] ? em->name : "(unnamed)",
                   em->kind == WX_EMITTER_POINT ? "point" : "hemisphere", em->center[0],
                   em->center[1], em->center[2]);
        }
        if (em->kind == WX_EMITTER_HEMISPHERE) {
            printf(" radius %g", em->radius);
        }
        printf(", %g/s from %g to %g s", em->rate, em->start, em->end);
        if (iterations > 1) {
            printf(" of each iteration (%lld particles per iteration, %lld in all)",
                   (long long)per_iteration, (long long)count);
        } else {
            printf(" (%lld particles)", (long long)count);
        }
        printf(", speed %g, mass %g, ", em->speed, em->mass);
        if (!scene.substances_declared) {
            printf("dirt %g", em->load[0]); // version 1's one substance
        } else {
            // The load of each substance a particle carries (the others: 0).
            int shown = 0;
            printf("loads");
            for (int k = 0; k < scene.substance_count; ++k) {
                if (em->load[k] != 0.0f) {
                    printf("%s %s %g", shown++ ? "," : "", scene.substances[k], em->load[k]);
                }
            }
            printf("%s", shown ? "" : " none");
        }
        printf(", max collisions %d\n", em->max_collisions);
    }
    printf("force fields (%d):\n", scene.field_count);
    for (int f = 0; f < scene.field_count; ++f) {
        const wx_field *fd = &scene.fields[f];
        printf("  %-12s ", field_name(fd->kind));
        switch (fd->kind) {
        case WX_FIELD_GRAVITY: printf("acceleration %g m/s^2 along -Y\n", fd->strength); break;
        case WX_FIELD_WIND:
            printf("force %g towards (%g, %g, %g)\n", fd->strength, fd->dir[0], fd->dir[1],
                   fd->dir[2]);
            break;
        case WX_FIELD_TURBULENCE:
            printf("strength %g, frequency %g, %d octaves\n", fd->strength, fd->frequency,
                   fd->octaves);
            break;
        }
    }
    const wx_collider_def *col = &scene.collider;
    printf("collider: resilience %g, friction %g, adherence %g, deposit %g, erosion %g\n",
           col->resilience, col->friction, col->adherence, col->deposit, col->erosion);
    // The global ageing rules, run on every surface texel after each iteration
    // before the texel's own surface's.
    bool ageing = wx_scene_has_ageing(&scene);
    if (ageing && scene.rule_count == 0) {
        printf("ageing: no global rule\n");
    } else if (ageing) {
        printf("ageing: %d global rule%s after each of the %d iteration%s: ", scene.rule_count,
               scene.rule_count == 1 ? "" : "s", iterations, iterations == 1 ? "" : "s");
        print_rules(&scene, scene.rules, scene.rule_count);
        printf("\n");
    }
    print_masks(&scene, opts.threads);
    printf("meshes (%d):\n", scene.mesh_count);
    for (int m = 0; m < scene.mesh_count; ++m) {
        const wx_mesh *mesh = &scene.meshes[m];
        printf("  %s:", mesh->path);
        for (int s = 0; s < mesh->surface_count && !ageing; ++s) {
            // Version 1's one substance: every surface on the mesh's line.
            const wx_surface *sf = &mesh->surfaces[s];
            printf("%s material '%s' absorption %g bounce %g dirt %g deposit %g erosion %g",
                   s ? ";" : "", sf->material, sf->absorption, sf->bounce, sf->initial[0],
                   sf->deposit[0], sf->erosion[0]);
        }
        printf("\n");
        for (int s = 0; s < mesh->surface_count && ageing; ++s) {
            // A line per surface: its exchange with each substance it trades
            // (the others: initial, deposit and erosion 0), and its own rules.
            const wx_surface *sf = &mesh->surfaces[s];
            printf("    material '%s' absorption %g bounce %g; exchanges", sf->material,
                   sf->absorption, sf->bounce);
            int shown = 0;
            for (int k = 0; k < scene.substance_count; ++k) {
                if (sf->initial[k] != 0.0f || sf->deposit[k] != 0.0f || sf->erosion[k] != 0.0f) {
                    printf("%s %s initial %g deposit %g erosion %g", shown++ ? "," : "",
                           scene.substances[k], sf->initial[k], sf->deposit[k], sf->erosion[k]);
                }
            }
            printf("%s", shown ? "" : " none");
            if (sf->rule_count > 0) {
                printf("; rules ");
                print_rules(&scene, sf->rules, sf->rule_count);
            }
            printf("\n");
        }
        if (imported) {
            const wx_geometry_mesh *g = &geometry.meshes[m];
            char shown[WX_ERROR_MAX];
            printf("    %lld triangles, %lld vertices, bounds (%g, %g, %g) to (%g, %g, %g)\n",
                   (long long)g->data.triangle_count, (long long)g->data.vertex_count,
                   g->data.bounds_min[0], g->data.bounds_min[1], g->data.bounds_min[2],
                   g->data.bounds_max[0], g->data.bounds_max[1], g->data.bounds_max[2]);
            print_frames(&scene, &g->data);
            for (int k = 0; k < g->data.material_count; ++k) {
                wx_printable(g->data.material_names[k], shown, sizeof shown);
                printf("    material '%s' -> <Surface material=\"%s\">\n", shown,
                       mesh->surfaces[g->surface[k]].material);
            }
        }
    }
    if (imported) {
        // Cameras that would bake nothing (a mesh without thickness, edge-on).
        wx_geometry_warn_blind(&scene, &geometry, scene.path, args->quiet);
    }
    for (int t = 0; t < scene.texture_count; ++t) {
        print_texture(&scene, &scene.textures[t], &geometry.meshes[scene.textures[t].mesh].data);
    }
    // The pilot uses the geometry up (its arrays go to the renderer).
    wx_pilot_report pilot;
    wx_error pilot_err;
    wx_memory_need need;
    wx_memory_estimate_geometry(&scene, WX_PHASE_ALL, imported ? &geometry : NULL, &need);
    wx_result pilot_r = wx_pilot_run(&scene, &opts, &geometry, &pilot, &pilot_err);
    wx_geometry_free(&geometry);
    double available = wx_memory_available();
    const double mib = 1024.0 * 1024.0;
    char frame[96] = "";
    if (need.frame_bytes > 0.0) {
        snprintf(frame, sizeof frame, " and %.0f for a frame of the mask's sequence",
                 need.frame_bytes / mib);
    }
    printf("memory: about %.0f MiB at the peak (the %s: program %.0f, bake %.0f with %.0f for "
           "the meshes, simulation %.0f with %.0f for at most %.0f particles alive at once of "
           "%.0f emitted%s, gather %.0f; MiB)",
           need.total_bytes / mib, need.phase, need.baseline_bytes / mib, need.bake_bytes / mib,
           need.mesh_bytes / mib, (need.sim_map_bytes + need.particle_bytes) / mib,
           need.particle_bytes / mib, need.particles_alive, need.particles, frame,
           need.gather_bytes / mib);
    if (available >= 0.0) {
        printf(" of %.0f MiB available%s", available / (1024.0 * 1024.0),
               need.total_bytes > available ? ": too much, a run would be refused" : "");
    }
    printf("\n");
    if (pilot_r != WX_OK) {
        printf("pilot: not flown (%s)\n", pilot_err.message);
    } else if (pilot.particles > 0) {
        double n = (double)pilot.particles;
        double wasted = 100.0 * (double)pilot.escaped_without_hit / n;
        printf("pilot: %lld particles on maps of at most %d texels a side: %.1f%% would leave the "
               "bounding box without a hit, %.1f%% would still fly at the end (%.2f s)%s\n",
               (long long)pilot.particles, WX_PILOT_SIDE, wasted,
               100.0 * (double)pilot.alive / n, pilot.seconds,
               wasted > 50.0 ? "; over half: aim the emitters at the model (a <BoxEmitter> "
                               "above or beside it)"
                             : "");
    }
    printf("output folder: %s\n", opts.out_dir);
    if (opts.stats_path != NULL) {
        char shown[WX_ERROR_MAX];
        wx_printable(opts.stats_path, shown, sizeof shown);
        printf("statistics: %s (written by bake, simulate, gather and run; info writes nothing)\n",
               shown);
    }
    wx_scene_free(&scene);
    return 0;
}
