// Image error of a run against its reference run, on the 8-bit images the renderer wrote.
#pragma once
#include <filesystem>
#include <optional>

namespace bvhlab {

struct ImageError {
  double meanAbsError = 0.0;  // mean |a - b| over all pixels and the R, G, B channels, in 8-bit units (0..255)
  double mse = 0.0;           // mean squared error, same units
  // Peak signal-to-noise ratio 10 log10(255^2 / MSE) in dB; empty when the images are identical
  // (MSE 0: PSNR is infinite).
  std::optional<double> psnr() const;
};

// Compares two 8-bit PNGs (alpha ignored). Throws InputError naming a file that cannot be read, and
// std::invalid_argument when the sizes differ.
ImageError compareImages(const std::filesystem::path& image, const std::filesystem::path& reference);

}  // namespace bvhlab
