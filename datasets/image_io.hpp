// Image files in and out (OpenImageIO). In memory every image is bottom-up (row 0 is v = 0, the GL
// convention); files are top-down, so every reader and writer here flips.
//
// Colour: loadImage returns linear RGBA. 8/16-bit integer files (PNG, JPEG, ...) are sRGB-encoded and
// are decoded to linear unless the file declares itself linear; float files (EXR, HDR) are linear.
// Alpha is never decoded. Writers are atomic: they write a temporary file beside the target and
// rename it, so a failed or interrupted write never leaves a partial image at the target path.
#pragma once
#include <cstdint>
#include <filesystem>
#include <vector>

#include "datasets/scene.hpp"

namespace bvhlab {

// Any format OpenImageIO reads -> linear RGBA32F, bottom-up. 1 channel = grey, 2 = grey + alpha,
// 3 = RGB (alpha 1), 4+ = RGBA (extra channels dropped). Throws InputError naming the path for a
// missing, unreadable, empty, oversized (> 2^28 pixels) or unsupported file.
Image loadImage(const std::filesystem::path& path);

// An 8-bit RGBA image exactly as stored (no colour conversion), bottom-up.
struct ImageRgba8 {
  int width = 0, height = 0;
  std::vector<uint8_t> rgba;  // 4 * width * height bytes
};

// Reads an 8-bit file (PNG) back to its stored bytes, bottom-up (for tests that compare images).
// Throws InputError for a missing or unreadable file, or a file that is not 8 bits per channel.
ImageRgba8 loadImageRgba8(const std::filesystem::path& path);

// The OpenImageIO writer an 8-bit image file gets from its extension (case-insensitive): .png (and
// a name without an extension) -> "png", .jpg/.jpeg -> "jpeg" (alpha dropped), .tif/.tiff -> "tiff".
// Anything else, .exr included (the render is 8-bit display-referred, not scene-linear), throws
// InputError naming the path and the formats that work: call it before rendering.
std::string imageFormatFor(const std::filesystem::path& path);

// Writes 8-bit RGBA (bottom-up, e.g. straight from glReadPixels) in the format imageFormatFor(path)
// names. Creates parent directories. Throws std::invalid_argument if the buffer size is not 4*w*h,
// InputError naming the path if the file cannot be written or its extension names no 8-bit format.
void saveImageRgba8(const std::filesystem::path& path, int width, int height,
                    const std::vector<uint8_t>& rgbaBottomUp);

// Writes a linear float image as a 32-bit float RGBA OpenEXR. Same guarantees as saveImageRgba8.
void saveImageExr(const std::filesystem::path& path, const Image& image);

// IEC 61966-2-1 sRGB transfer functions (per channel, input clamped to [0,1] for the encode).
float srgbToLinear(float encoded);
float linearToSrgb(float linear);

// Linear float image -> 8-bit sRGB RGBA bytes (alpha linear), bottom-up: for previews of textures.
std::vector<uint8_t> encodeSrgb8(const Image& image);

}  // namespace bvhlab
