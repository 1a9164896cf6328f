// Sonar speckle from the physics of a coherent echo, and the display codings real sonars use. No
// OpenGL: SonarRenderer applies it to every ping; tests check its statistics directly.
//
// Speckle. The echo of a resolution cell is the coherent sum of many scatterers: a complex
// Gaussian amplitude, so an exponential intensity (Rayleigh amplitude) of unit mean. Neighbouring
// cells share scatterers through the beam pattern (across beams) and the pulse length (along
// range): the complex field is white noise filtered by a Gaussian kernel whose intensity
// autocorrelation has a full width at half maximum of `grain_beams` and `grain_bins` cells (the
// kernel is normalised, so the marginal stays exponential). Sparse scatterers (a few per cell, as
// on a real seabed) make the intensity K-distributed: the exponential speckle times a Gamma texture
// of shape `shape` and unit mean (the scatterers' density: constant over patches of about twice
// the grain), so the intensity's contrast (std / mean) is sqrt(1 + 2 / shape) (1 for shape ->
// infinity; shape = 0 here means no texture: Rayleigh). The white field is drawn from a table of
// 4096 exact complex Gaussians by random index (12 bits of the seeded stream a sample).
//
// Side lobes. A fan's beams are formed from one receive array: beam c also hears, at every
// range, what beam c' sees, weighted by its power pattern d = c' - c beams off its axis. The main
// lobe is the beam's own cell; outside it the side lobes' envelope is
//   k(d) = 10^(sidelobe_db / 10) (1.5 / |d|)^(falloff_db_per_octave / (10 log10 2)),  |d| >= 1.5,
// 0 for 0 < |d| < 1.5 (a line array's first side lobe sits ~1.5 beam widths off the axis). Added
// to the linear intensity before speckle and noise (the leaked echo speckles like any other).
//
// Display. An 8-bit sample from a linear intensity v (full scale: v = 10^(-gain_db / 10)):
//   db:    255 (1 + 10 log10(v / full) / dynamic_range_db), clamped to [0, 255]
//   gamma: 255 (v / full)^(gamma / 2) (amplitude to the power gamma), clamped; v > full saturates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "unav_common/sampling.hpp"

namespace unav::renderer {

struct SpeckleParams {
  double shape = 0.0;        ///< K-distribution shape nu (> 0); 0 = Rayleigh (no texture)
  double grain_beams = 1.0;  ///< FWHM of the intensity autocorrelation across beams [cells]; <= 1: independent
  double grain_bins = 1.0;   ///< the same along range [bins]
};

/// A unit-mean speckle field of bins x channels (row = bin) into *out, drawn from *rng.
void speckle_field(int bins, int channels, const SpeckleParams& p, unav::common::SplitMix64* rng,
                   std::vector<float>* out);

/// The Gaussian kernel (normalised to unit sum of squares) whose intensity autocorrelation has a
/// FWHM of `grain` cells: a single 1 for grain <= 1.
std::vector<double> speckle_kernel(double grain);

/// k(d) for d = 0 .. channels - 1 (k(0) = 0: the main lobe is the cell itself).
std::vector<double> sidelobe_kernel(int channels, double sidelobe_db, double falloff_db_per_octave);

/// field (bins x channels, row = bin) += its side-lobe leakage: each cell gains sum over the other
/// beams c' of its row of k(|c - c'|) field[c'] (row by row through the DFT: O(channels log
/// channels) a row).
void add_sidelobes(int bins, int channels, const std::vector<double>& kernel, std::vector<double>* field);

/// The coding is chosen and its constants computed once: operator() runs for every sample of a ping.
class DisplayCoding {
 public:
  /// coding: db or gamma; dynamic_range_db for db, gamma (the exponent on the amplitude) for gamma.
  explicit DisplayCoding(const std::string& coding = "db", double gain_db = 0.0, double dynamic_range_db = 60.0,
                         double gamma = 0.5);
  /// The 8-bit sample of linear intensity v.
  std::uint8_t operator()(double v) const;

 private:
  bool gamma_;
  double gain_db_, dynamic_range_db_, exponent_, gain_;
};

}  // namespace unav::renderer
