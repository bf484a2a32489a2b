#include "datasets/image_io.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

#include <OpenImageIO/imageio.h>

namespace bvhlab {
namespace fs = std::filesystem;

namespace {

// Guards against absurd headers (a 2^28-pixel RGBA32F image is already 4 GiB).
constexpr int64_t kMaxPixels = int64_t(1) << 28;
// A tiled file's tile may cover up to the whole image, or up to this many pixels (256x256, more than
// the tile sizes writers use) for a small image. A larger tile holds only pixels that do not exist,
// yet readers allocate buffers for it: a fuzzed 20x18 EXR declaring 8,257,552x16 tiles made OpenEXR
// and OpenImageIO allocate 14 GB (tests/fuzz/regressions/exr/).
constexpr int64_t kMaxSmallImageTilePixels = int64_t(1) << 16;

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}
// A file that is missing or cannot be written, as opposed to one whose content is refused.
[[noreturn]] void failFile(const fs::path& path, const std::string& what) {
  throw FileError(path.string() + ": " + what);
}

// OIIO error text can span lines; our messages are one line.
std::string oneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s.empty() ? std::string("unknown OpenImageIO error") : s;
}

// An OpenEXR file's headers, walked before OpenEXR reads them: the C++ library allocates each
// attribute's value at the size the header declares, so a 368-byte fuzzed file declaring a 1.8 GB string
// attribute took 1.9 GB before it failed (tests/fuzz/regressions/exr/). Per the OpenEXR file layout: the
// magic number and version (8 bytes), then one header (several in a multi-part file, ended by an empty
// one), each a list of attributes (name and type, each at most 255 characters and a null, a 4-byte
// little-endian size, the value) ended by a null. Refuses an attribute whose size is negative or runs past
// the end of the file; anything else is left to OpenEXR.
void checkExrHeaders(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t n = bytes.size();
  if (n < 8 || uint8_t(bytes[0]) != 0x76 || uint8_t(bytes[1]) != 0x2f || uint8_t(bytes[2]) != 0x31 ||
      uint8_t(bytes[3]) != 0x01)
    return;  // not OpenEXR: the extension lied, and OpenImageIO will say what it is
  const bool multipart = (uint8_t(bytes[5]) & 0x10) != 0;  // version bit 12
  size_t at = 8;
  auto cstring = [&](const char* what) {
    const size_t start = at;
    while (at < n && bytes[at] != 0 && at - start < 256) ++at;
    if (at >= n || bytes[at] != 0) fail(path, std::string("OpenEXR header: an attribute ") + what + " is not terminated");
    return std::string(bytes.data() + start, bytes.data() + at++);
  };
  for (;;) {  // headers
    if (at >= n) fail(path, "OpenEXR header: the file ends inside its header");
    if (bytes[at] == 0) return;  // an empty header: the end of a multi-part file's headers
    while (at < n && bytes[at] != 0) {  // attributes
      const std::string name = cstring("name"), type = cstring("type");
      if (n - at < 4) fail(path, "OpenEXR header: attribute '" + name + "' has no size");
      const int32_t size = int32_t(uint32_t(uint8_t(bytes[at])) | uint32_t(uint8_t(bytes[at + 1])) << 8 |
                                   uint32_t(uint8_t(bytes[at + 2])) << 16 | uint32_t(uint8_t(bytes[at + 3])) << 24);
      at += 4;
      if (size < 0 || size_t(size) > n - at)
        fail(path, "OpenEXR header: attribute '" + name + "' (" + type + ") declares " + std::to_string(size) +
                       " bytes; " + std::to_string(n - at) + " are left in the file");
      at += size_t(size);
    }
    if (at >= n) fail(path, "OpenEXR header: the file ends inside its header");
    ++at;  // the header's null
    if (!multipart) return;
  }
}

std::unique_ptr<OIIO::ImageInput> openInput(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) failFile(path, "image file not found");
  if (!fs::is_regular_file(path, ec)) fail(path, "not a regular file");
  checkExrHeaders(path);
  // Keep alpha unassociated (straight), as stored in PNG: by default OIIO premultiplies on read.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) fail(path, "cannot read image (" + oneLine(OIIO::geterror()) + ")");
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) fail(path, "empty image");
  if (spec.depth > 1) fail(path, "volume images are not supported");
  if (int64_t(spec.width) * spec.height > kMaxPixels)
    fail(path, "image too large (" + std::to_string(spec.width) + "x" + std::to_string(spec.height) + ")");
  const int64_t tilePixels = int64_t(std::max(spec.tile_width, 0)) * std::max(spec.tile_height, 1);
  if (tilePixels > std::max(int64_t(spec.width) * spec.height, kMaxSmallImageTilePixels))
    fail(path, "tiles larger than the image (" + std::to_string(spec.tile_width) + "x" +
                   std::to_string(spec.tile_height) + " tiles of a " + std::to_string(spec.width) + "x" +
                   std::to_string(spec.height) + " image)");
  return in;
}

// Whether integer pixel data in this file is sRGB-encoded: yes unless the file says it is linear.
bool isSrgbEncoded(const OIIO::ImageSpec& spec) {
  if (spec.format.is_floating_point()) return false;
  std::string cs = spec.get_string_attribute("oiio:ColorSpace");
  std::transform(cs.begin(), cs.end(), cs.begin(), [](unsigned char c) { return std::tolower(c); });
  return cs != "linear" && cs != "scene_linear";
}

std::string uniqueSuffix() {
  static std::atomic<unsigned> counter{0};
  return ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

// Writes through `write(tmpPath)` to a sibling temporary file, then renames it over `path`.
template <class WriteFn>
void writeAtomically(const fs::path& path, WriteFn&& write) {
  std::error_code ec;
  const fs::path dir = path.parent_path();
  if (!dir.empty()) {
    fs::create_directories(dir, ec);
    if (ec) failFile(path, "cannot create directory " + dir.string() + " (" + ec.message() + ")");
  }
  fs::path tmp = path;
  tmp += uniqueSuffix();
  try {
    write(tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    failFile(path, "cannot rename temporary file into place (" + ec.message() + ")");
  }
}

// One image out through OIIO, bottom-up rows (negative y stride walks the buffer from its last row).
void writeOiio(const fs::path& path, const fs::path& tmp, const char* format, const OIIO::ImageSpec& spec,
               const void* bottomUp, size_t rowBytes) {
  auto out = OIIO::ImageOutput::create(format);
  if (!out) fail(path, std::string("no OpenImageIO writer for ") + format);
  if (!out->open(tmp.string(), spec)) failFile(path, "cannot write image (" + oneLine(out->geterror()) + ")");
  const auto* lastRow = static_cast<const uint8_t*>(bottomUp) + rowBytes * size_t(spec.height - 1);
  bool ok = out->write_image(spec.format, lastRow, OIIO::AutoStride, -OIIO::stride_t(rowBytes));
  ok = out->close() && ok;
  if (!ok) failFile(path, "cannot write image (" + oneLine(out->geterror()) + ")");
}

}  // namespace

float srgbToLinear(float encoded) {
  // IEC 61966-2-1: linear segment below 0.04045, power 2.4 above.
  if (encoded <= 0.04045f) return encoded / 12.92f;
  return std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

float linearToSrgb(float linear) {
  // Negatives and NaN encode as black (NaN fails the comparison); above 1 clips to white.
  const float c = linear > 0.0f ? std::min(linear, 1.0f) : 0.0f;
  if (c <= 0.0031308f) return 12.92f * c;
  return 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

Image loadImage(const fs::path& path) {
  auto in = openInput(path);
  const OIIO::ImageSpec spec = in->spec();
  const int w = spec.width, h = spec.height, nch = std::min(spec.nchannels, 4);
  const bool srgb = isSrgbEncoded(spec);
  const bool hasAlpha = nch == 2 || nch == 4;
  Image img;
  img.width = w;
  img.height = h;
  img.name = path.string();

  // Decoded in bands of rows, and the texels grow with the rows decoded: memory follows what the
  // file holds, not what its header claims. (Decoding the whole image at once first allocated and
  // zeroed w x h x channels floats: a 40-byte HDR file claiming 16000 x 16000 pixels took 3 GB and
  // 18 s before its decoder failed; tests/fuzz/regressions/hdr/.) A band is about 4 MiB of floats,
  // or one row (tiled files: one row of tiles).
  const size_t rowFloats = size_t(w) * nch;
  const int tileRows = spec.tile_width > 0 && spec.tile_height > 0 ? spec.tile_height : 1;
  const int bandRows = std::max(1, int(std::min<size_t>((size_t(1) << 20) / rowFloats, size_t(h)) / tileRows)) * tileRows;
  std::vector<float> band;
  for (int top = 0; top < h; top += bandRows) {
    const int rows = std::min(bandRows, h - top);
    band.resize(rowFloats * size_t(rows));
    const int y0 = spec.y + top, y1 = y0 + rows;
    const bool ok = spec.tile_width > 0
                        ? in->read_tiles(0, 0, spec.x, spec.x + w, y0, y1, spec.z, spec.z + 1, 0, nch,
                                         OIIO::TypeDesc::FLOAT, band.data())
                        : in->read_scanlines(0, 0, y0, y1, spec.z, 0, nch, OIIO::TypeDesc::FLOAT, band.data());
    if (!ok) fail(path, "cannot decode image (" + oneLine(in->geterror()) + ")");
    img.texels.resize(size_t(w) * size_t(top + rows));  // file rows top..top+rows-1, top-down for now
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < w; ++x) {
        const float* p = band.data() + size_t(y) * rowFloats + size_t(x) * nch;
        glm::vec3 rgb = nch >= 3 ? glm::vec3(p[0], p[1], p[2]) : glm::vec3(p[0]);
        if (srgb) rgb = glm::vec3(srgbToLinear(rgb.r), srgbToLinear(rgb.g), srgbToLinear(rgb.b));
        const float a = hasAlpha ? p[nch - 1] : 1.0f;
        img.texels[size_t(top + y) * w + x] = glm::vec4(rgb, a);
      }
  }
  in->close();
  // File row h-1-y is our row y.
  for (int y = 0; y < h / 2; ++y)
    std::swap_ranges(img.texels.begin() + ptrdiff_t(size_t(y) * w), img.texels.begin() + ptrdiff_t(size_t(y + 1) * w),
                     img.texels.begin() + ptrdiff_t(size_t(h - 1 - y) * w));
  for (const glm::vec4& t : img.texels)
    if (!std::isfinite(t.r) || !std::isfinite(t.g) || !std::isfinite(t.b) || !std::isfinite(t.a))
      fail(path, "image contains NaN or infinite values");
  return img;
}

ImageRgba8 loadImageRgba8(const fs::path& path) {
  auto in = openInput(path);
  const OIIO::ImageSpec spec = in->spec();
  if (spec.format != OIIO::TypeDesc::UINT8) fail(path, "not an 8-bit image (" + std::string(spec.format.c_str()) + ")");
  const int w = spec.width, h = spec.height, nch = std::min(spec.nchannels, 4);
  std::vector<uint8_t> raw(size_t(w) * h * nch);
  if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::UINT8, raw.data()))
    fail(path, "cannot decode image (" + oneLine(in->geterror()) + ")");
  in->close();

  ImageRgba8 img;
  img.width = w;
  img.height = h;
  img.rgba.resize(size_t(w) * h * 4);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = raw.data() + (size_t(h - 1 - y) * w + x) * nch;
      uint8_t* q = img.rgba.data() + (size_t(y) * w + x) * 4;
      q[0] = p[0];
      q[1] = nch >= 3 ? p[1] : p[0];
      q[2] = nch >= 3 ? p[2] : p[0];
      q[3] = (nch == 2 || nch == 4) ? p[nch - 1] : 255;
    }
  return img;
}

void saveImageRgba8(const fs::path& path, int width, int height, const std::vector<uint8_t>& rgbaBottomUp) {
  if (width <= 0 || height <= 0 || rgbaBottomUp.size() != size_t(width) * height * 4)
    throw std::invalid_argument("saveImageRgba8(" + path.string() + "): buffer of " +
                                std::to_string(rgbaBottomUp.size()) + " bytes for a " + std::to_string(width) +
                                "x" + std::to_string(height) + " RGBA8 image");
  const std::string format = imageFormatFor(path);
  if (format == "jpeg") {  // JPEG has no alpha channel: write RGB
    std::vector<uint8_t> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < size_t(width) * height; ++i)
      for (int c = 0; c < 3; ++c) rgb[3 * i + c] = rgbaBottomUp[4 * i + c];
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    spec.attribute("Compression", "jpeg:95");
    writeAtomically(path, [&](const fs::path& tmp) { writeOiio(path, tmp, "jpeg", spec, rgb.data(), size_t(width) * 3); });
    return;
  }
  OIIO::ImageSpec spec(width, height, 4, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // the bytes are straight alpha: write them as they are
  writeAtomically(path, [&](const fs::path& tmp) {
    writeOiio(path, tmp, format.c_str(), spec, rgbaBottomUp.data(), size_t(width) * 4);
  });
}

std::string imageFormatFor(const fs::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext.empty() || ext == ".png") return "png";
  if (ext == ".jpg" || ext == ".jpeg") return "jpeg";
  if (ext == ".tif" || ext == ".tiff") return "tiff";
  const std::string why = ext == ".exr" ? " (the render is 8-bit display-referred, not scene-linear)" : "";
  throw InputError(path.string() + ": cannot write an 8-bit image as '" + ext + "'" + why +
                   "; use .png, .jpg/.jpeg or .tif/.tiff");
}

void saveImageExr(const fs::path& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 || image.texels.size() != size_t(image.width) * image.height)
    throw std::invalid_argument("saveImageExr(" + path.string() + "): image size does not match its texels");
  OIIO::ImageSpec spec(image.width, image.height, 4, OIIO::TypeDesc::FLOAT);
  spec.attribute("compression", "zip");
  writeAtomically(path, [&](const fs::path& tmp) {
    writeOiio(path, tmp, "openexr", spec, image.texels.data(), size_t(image.width) * sizeof(glm::vec4));
  });
}

std::vector<uint8_t> encodeSrgb8(const Image& image) {
  std::vector<uint8_t> out(image.texels.size() * 4);
  auto quantise = [](float v) {  // NaN -> 0 (fails the comparison)
    return uint8_t(std::lround((v > 0.0f ? std::min(v, 1.0f) : 0.0f) * 255.0f));
  };
  for (size_t i = 0; i < image.texels.size(); ++i) {
    const glm::vec4 t = image.texels[i];
    out[4 * i + 0] = quantise(linearToSrgb(t.r));
    out[4 * i + 1] = quantise(linearToSrgb(t.g));
    out[4 * i + 2] = quantise(linearToSrgb(t.b));
    out[4 * i + 3] = quantise(t.a);
  }
  return out;
}

}  // namespace bvhlab
