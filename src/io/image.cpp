#include "zeroset/io/image.h"

#include <algorithm>
#include <cmath>

#include <zlib.h>

#include <cstdlib>

namespace {
// stb's own deflate is slow and compresses poorly; zlib at a fast level is several times
// quicker for the same or smaller files. stb frees the result with free().
unsigned char* zlib_compress(unsigned char* data, int size, int* out_size, int /*quality*/) {
  uLongf bound = compressBound(static_cast<uLong>(size));
  auto* out = static_cast<unsigned char*>(std::malloc(bound));
  if (!out) return nullptr;
  if (compress2(out, &bound, data, static_cast<uLong>(size), 1) != Z_OK) {
    std::free(out);
    return nullptr;
  }
  *out_size = static_cast<int>(bound);
  return out;
}
}  // namespace

#define STBIW_ZLIB_COMPRESS zlib_compress
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb_image.h>
#include <stb_image_write.h>

#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {

void Image::set_linear(int x, int y, const Color& c) {
  std::uint8_t* p = pixel(x, y);
  for (int k = 0; k < 3; ++k) {
    const double v = std::clamp(c[k], 0.0, 1.0);
    p[k] = static_cast<std::uint8_t>(std::lround(std::pow(v, 1.0 / 2.2) * 255.0));
  }
}

void write_png(const Image& image, const std::string& path) {
  if (image.width <= 0 || image.height <= 0) throw IoError(path, "image is empty");
  stbi_write_force_png_filter = 2;  // "up" filter: nearly as small as adaptive, much faster
  write_file_atomically(path, [&](std::ostream& out) {
    auto sink = [](void* ctx, void* data, int size) {
      static_cast<std::ostream*>(ctx)->write(static_cast<const char*>(data), size);
    };
    if (!stbi_write_png_to_func(sink, &out, image.width, image.height, 3, image.rgb.data(),
                                image.width * 3))
      throw IoError(path, "PNG encoding failed");
  });
}

Image read_image(const std::string& path) {
  const std::string bytes = read_text_file(path);
  int w = 0, h = 0, n = 0;
  unsigned char* data =
      stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                            static_cast<int>(bytes.size()), &w, &h, &n, 3);
  if (!data) throw IoError(path, std::string("not a readable PNG: ") + stbi_failure_reason());
  Image img(w, h);
  std::copy(data, data + static_cast<size_t>(w) * h * 3, img.rgb.begin());
  stbi_image_free(data);
  return img;
}

}  // namespace zeroset
