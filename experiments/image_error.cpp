#include "experiments/image_error.hpp"

#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "datasets/image_io.hpp"

namespace bvhlab {

std::optional<double> ImageError::psnr() const {
  if (mse == 0.0) return std::nullopt;
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

ImageError compareImages(const std::filesystem::path& image, const std::filesystem::path& reference) {
  const ImageRgba8 a = loadImageRgba8(image);
  const ImageRgba8 b = loadImageRgba8(reference);
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("image " + image.string() + " is " + std::to_string(a.width) + "x" +
                                std::to_string(a.height) + " but its reference " + reference.string() + " is " +
                                std::to_string(b.width) + "x" + std::to_string(b.height));
  ImageError e;
  const size_t pixels = size_t(a.width) * size_t(a.height);
  if (pixels == 0) return e;
  uint64_t absSum = 0, sqSum = 0;  // exact integer sums: 255^2 * 3 * 2^28 pixels fits in 64 bits
  for (size_t p = 0; p < pixels; ++p)
    for (size_t c = 0; c < 3; ++c) {
      const int d = int(a.rgba[4 * p + c]) - int(b.rgba[4 * p + c]);
      absSum += uint64_t(std::abs(d));
      sqSum += uint64_t(d * d);
    }
  const double samples = double(pixels) * 3.0;
  e.meanAbsError = double(absSum) / samples;
  e.mse = double(sqSum) / samples;
  return e;
}

}  // namespace bvhlab
