// noise.h: the Noise mask (docs/design.md section 15, docs/masks.md): fractal
// Perlin noise of a surface point's world position, remapped by its rank over
// the surface's area so that its values are uniform on [0, 1].
//
// The remap is one monotone function of the raw noise for the whole scene (a
// table of the raw value's quantiles over an area-weighted sample of every
// surface), so the same world point has the same value from every camera,
// layer and TextureMap: no seams. The noise itself hashes integer lattice
// points with the mask's seed; no global state.
#ifndef WX_NOISE_H
#define WX_NOISE_H

#include <stddef.h>
#include <stdint.h>

#include "model/mesh.h"
#include "model/scene.h"

/// Entries of a remap table: the raw value's quantiles at k / (size - 1).
#define WX_NOISE_TABLE_SIZE 4097

/// Points of the area-weighted sample a table is built from, at most.
#define WX_NOISE_SAMPLE_POINTS (1 << 18)

/// Fractal Perlin noise of world point p: the sum over `octaves` octaves o of
/// gain^o * perlin(p * frequency * 2^o, seed, o), each octave's lattice hashed
/// with the seed and the octave. About [-1, 1] for gain 0.5; 0 at the lattice.
double wx_noise_fbm(const double p[3], double frequency, int octaves, double gain, uint64_t seed);

/// Noise mask `mask`'s raw value at p (wx_noise_fbm with its parameters).
double wx_noise_raw(const wx_mask_def *mask, const double p[3]);

/// Fills table[WX_NOISE_TABLE_SIZE] with the quantiles of mask's raw value over
/// `count` points (3 doubles each, world) weighted by `weight` (the area each
/// stands for; NULL: equal). No points: the identity of [-1, 1]. Returns
/// WX_FAIL on want of memory.
wx_result wx_noise_table_build(const wx_mask_def *mask, const double *points, const double *weight,
                               size_t count, double *table, wx_error *err);

/// The value in [0, 1] of raw value `raw` under a table: the fraction of the
/// sample's weight below it, interpolated linearly between quantiles.
float wx_noise_remap(const double *table, double raw);

/// An area-weighted sample of the triangles of `count` meshes: `samples` world
/// points (3 doubles each, into out), stratified along the meshes' cumulative
/// area, each inside its triangle at a hash of its index (the same points
/// every run). Returns the number written (0 when the meshes have no area).
size_t wx_noise_sample_meshes(const wx_mesh_data *const *meshes, int count, size_t samples,
                              double *out);

#endif
