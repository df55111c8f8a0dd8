#pragma once
/// 8-bit RGB images and their files: PNG (compressed) and binary PPM (uncompressed).
#include <cstdint>
#include <string>
#include <vector>

#include "zeroset/types.h"

namespace zeroset {

/// Row-major RGB image, row 0 at the top.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< width*height*3 bytes

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, 0) {}
  std::uint8_t* pixel(int x, int y) { return &rgb[(static_cast<size_t>(y) * width + x) * 3]; }
  const std::uint8_t* pixel(int x, int y) const {
    return &rgb[(static_cast<size_t>(y) * width + x) * 3];
  }
  /// Stores a linear colour (clamped, gamma 2.2 encoded).
  void set_linear(int x, int y, const Color& c);
};

/// The PNG file's bytes (8-bit RGB, zlib level 1), as write_png writes them: for front ends
/// that show a picture without a file. Throws InvalidArgument for an empty image.
std::vector<std::uint8_t> encode_png(const Image& image);
/// Writes a PNG (8-bit RGB, zlib level 1) atomically. Large pictures are compressed in bands
/// on all cores (an 800×800 picture in a few milliseconds). Throws IoError.
void write_png(const Image& image, const std::string& path);
/// Writes a binary PPM (P6, maxval 255; the netpbm format that ffmpeg and most image tools
/// read) atomically: no compression, so it is the fastest to write (a plain copy of the
/// pixels). Throws IoError.
void write_ppm(const Image& image, const std::string& path);
/// The picture file formats write_image knows, by file extension without the dot: png, ppm.
const std::vector<std::string>& image_file_extensions();
/// Writes `image` in the format of the extension of `path` (see image_file_extensions();
/// case-insensitive). Throws InvalidArgument for another extension, IoError when writing
/// fails.
void write_image(const Image& image, const std::string& path);
/// Reads a PNG or a binary PPM as RGB. Throws IoError.
Image read_image(const std::string& path);

}  // namespace zeroset
