// stats_json.c: the --stats file (stats_json.h).
#include "io/stats_json.h"

#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/atomic_file.h"

// The most memory this process has held resident, in MiB: the kernel's high
// water mark of its address space (VmHWM in /proc/self/status), which starts
// anew at exec, unlike getrusage's ru_maxrss, which keeps the parent's when a
// large process forks the run (a benchmark that ran a simulation itself
// measured its own memory as the run's). -1 where /proc does not say.
static double peak_memory_mib(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (f == NULL) {
        return -1.0;
    }
    char line[256];
    double kib = -1.0;
    while (fgets(line, sizeof line, f) != NULL) {
        if (strncmp(line, "VmHWM:", 6) == 0) {
            long long v = 0;
            if (sscanf(line + 6, "%lld", &v) == 1) {
                kib = (double)v;
            }
            break;
        }
    }
    fclose(f);
    return kib >= 0.0 ? kib / 1024.0 : -1.0;
}

// `text` as a JSON string's contents: quotes, backslashes and control
// characters escaped. False when it does not fit in cap bytes.
static bool json_escape(const char *text, char *out, size_t cap)
{
    size_t n = 0;
    for (const unsigned char *c = (const unsigned char *)text; *c != '\0'; ++c) {
        char piece[8];
        if (*c == '"' || *c == '\\') {
            snprintf(piece, sizeof piece, "\\%c", *c);
        } else if (*c < 0x20) {
            snprintf(piece, sizeof piece, "\\u%04x", *c);
        } else {
            piece[0] = (char)*c;
            piece[1] = '\0';
        }
        size_t len = strlen(piece);
        if (n + len >= cap) {
            return false;
        }
        memcpy(out + n, piece, len);
        n += len;
    }
    out[n] = '\0';
    return true;
}

// The "noise" object: `"FILE": {...}` per output, or "" when there is none.
// False when it does not fit in cap bytes.
static bool noise_json(const wx_noise_report *noise, char *out, size_t cap)
{
    out[0] = '\0';
    if (noise == NULL || noise->count == 0) {
        return true;
    }
    size_t used = 0;
    int m = snprintf(out, cap, "  \"noise\": {\n");
    for (int k = 0; k < noise->count && m >= 0 && (size_t)m < cap - used; ++k) {
        used += (size_t)m;
        const wx_noise_figures *f = &noise->items[k];
        char file[6 * WX_OUTPUT_NAME_MAX + 1];
        if (!json_escape(f->file, file, sizeof file)) {
            return false;
        }
        double share =
            f->surface_texels > 0 ? (double)f->capped_texels / (double)f->surface_texels : 0.0;
        m = snprintf(out + used, cap - used,
                     "    \"%s\": { \"aim\": %.7g, \"impacts_aimed_at\": %.7g, "
                     "\"surface_texels\": %lld, \"capped_texels\": %lld, \"capped_share\": "
                     "%.7g, \"capped_noise_median\": %.7g }%s\n",
                     file, f->aim, f->target_hits, (long long)f->surface_texels,
                     (long long)f->capped_texels, share, f->capped_noise,
                     k + 1 < noise->count ? "," : "");
    }
    if (m < 0 || (size_t)m >= cap - used) {
        return false;
    }
    used += (size_t)m;
    m = snprintf(out + used, cap - used, "  },\n");
    return m >= 0 && (size_t)m < cap - used;
}

wx_result wx_write_stats(const char *path, const wx_sim_stats *stats, const wx_phase_times *times,
                         const wx_noise_report *noise, int threads, uint64_t seed, wx_error *err)
{
    char dirt[1024] = "", substances[8192] = "";
    if (stats->dirt_index >= 0 || stats->substance_count == 0) {
        snprintf(dirt, sizeof dirt,
                 "  \"dirt\": {\n"
                 "    \"initial_surface\": %.17g,\n"
                 "    \"emitted\": %.17g,\n"
                 "    \"final_surface\": %.17g,\n"
                 "    \"in_flight\": %.17g,\n"
                 "    \"escaped\": %.17g\n"
                 "  },\n",
                 stats->dirt_initial_surface, stats->dirt_emitted, stats->dirt_final_surface,
                 stats->dirt_in_flight, stats->dirt_escaped);
    }
    size_t used = 0;
    for (int k = 0; k < stats->substance_count && k < WX_MAX_SUBSTANCES; ++k) {
        const wx_substance_ledger *l = &stats->substance[k];
        int m = snprintf(substances + used, sizeof substances - used,
                         "%s    \"%s\": { \"initial_surface\": %.17g, \"emitted\": %.17g, "
                         "\"grown\": %.17g, \"transferred_in\": %.17g, \"transferred_out\": "
                         "%.17g, \"decayed\": %.17g, \"final_surface\": %.17g, "
                         "\"in_flight\": %.17g, \"escaped\": %.17g }",
                         k > 0 ? ",\n" : "", stats->substance_names[k], l->initial_surface,
                         l->emitted, l->grown, l->transferred_in, l->transferred_out, l->decayed,
                         l->final_surface, l->in_flight, l->escaped);
        if (m < 0 || (size_t)m >= sizeof substances - used) {
            return wx_fail(err, WX_CAUSE_INTERNAL, "%s: statistics too long", path);
        }
        used += (size_t)m;
    }
    char tile[64] = "";
    if (stats->tiled) {
        snprintf(tile, sizeof tile, "  \"tile_particles\": %lld,\n",
                 (long long)stats->tile_particles);
    }
    // Each output's entry: its escaped name and six numbers.
    size_t noise_cap =
        64 + (size_t)(noise != NULL ? noise->count : 0) * (6 * WX_OUTPUT_NAME_MAX + 256);
    char *noise_text = malloc(noise_cap);
    if (noise_text == NULL) {
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory (statistics)", path);
    }
    if (!noise_json(noise, noise_text, noise_cap)) {
        free(noise_text);
        return wx_fail(err, WX_CAUSE_INTERNAL, "%s: statistics too long", path);
    }
    size_t json_cap = 16384 + strlen(noise_text);
    char *json = malloc(json_cap);
    if (json == NULL) {
        free(noise_text);
        return wx_fail(err, WX_CAUSE_OUT_OF_MEMORY, "%s: out of memory (statistics)", path);
    }
    int n = snprintf(
        json, json_cap,
        "{\n"
        "  \"particles_emitted\": %lld,\n"
        "%s"
        "  \"particle_steps\": %lld,\n"
        "  \"collisions\": %lld,\n"
        "  \"absorbed\": %lld,\n"
        "  \"settled\": %lld,\n"
        "  \"escaped\": %lld,\n"
        "  \"escaped_without_hit\": %lld,\n"
        "  \"alive\": %lld,\n"
        "  \"alive_without_hit\": %lld,\n"
        "%s"
        "  \"iterations\": %lld,\n"
        "  \"substances\": {\n%s\n  },\n"
        "  \"seconds\": {\n"
        "    \"load\": %.6f,\n"
        "    \"bake\": %.6f,\n"
        "    \"simulate\": %.6f,\n"
        "    \"gather\": %.6f,\n"
        "    \"total\": %.6f\n"
        "  },\n"
        "  \"simulate_seconds\": { \"read\": %.6f, \"setup\": %.6f, \"steps\": %.6f, "
        "\"write\": %.6f },\n"
        "  \"gather_seconds\": { \"read\": %.6f, \"compute\": %.6f, \"write\": %.6f },\n"
        "%s"
        "  \"threads\": %d,\n"
        "  \"peak_memory_mib\": %.1f,\n"
        "  \"seed\": %llu\n"
        "}\n",
        (long long)stats->particles_emitted, tile, (long long)stats->particle_steps,
        (long long)stats->collisions, (long long)stats->absorbed, (long long)stats->settled,
        (long long)stats->escaped, (long long)stats->escaped_without_hit, (long long)stats->alive,
        (long long)stats->alive_without_hit, dirt, (long long)stats->iterations, substances,
        times->load, times->bake, times->simulate, times->gather, times->total,
        times->simulate_detail.read, times->simulate_detail.setup, times->simulate_detail.compute,
        times->simulate_detail.write, times->gather_detail.read, times->gather_detail.compute,
        times->gather_detail.write, noise_text, threads, peak_memory_mib(),
        (unsigned long long)seed);
    free(noise_text);
    wx_result r = n < 0 || (size_t)n >= json_cap
                      ? wx_fail(err, WX_CAUSE_INTERNAL, "%s: statistics too long", path)
                      : wx_write_file_atomic(path, json, (size_t)n, err);
    free(json);
    return r;
}

