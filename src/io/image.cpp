#include "zeroset/io/image.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <new>
#include <sstream>
#include <thread>

#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_PNM
#include <stb_image.h>

#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {
namespace {

// Rows are compressed in parts of at least this many bytes, one part per core: an 800×800
// picture (1.9 MB) takes two.
constexpr size_t kMinPartBytes = 512 * 1024;

void append_u32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8)
    out.push_back(static_cast<unsigned char>(v >> shift));
}

/// A PNG chunk: length, type, data, CRC of type and data.
void write_chunk(std::ostream& out, const char* type, const unsigned char* data, size_t size) {
  std::vector<unsigned char> head;
  append_u32(head, static_cast<std::uint32_t>(size));
  head.insert(head.end(), type, type + 4);
  uLong crc = crc32(0L, head.data() + 4, 4);
  if (size > 0) crc = crc32_z(crc, data, size);
  std::vector<unsigned char> tail;
  append_u32(tail, static_cast<std::uint32_t>(crc));
  out.write(reinterpret_cast<const char*>(head.data()), static_cast<std::streamsize>(head.size()));
  if (size > 0) out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.write(reinterpret_cast<const char*>(tail.data()), static_cast<std::streamsize>(tail.size()));
}

/// Rows [y0, y1) of the image as PNG scanlines (filter type 0: a smoothly shaded picture
/// compresses as well unfiltered as with the "up" or "sub" filters, and faster) deflated
/// into a raw stream (no zlib header) that ends byte-aligned, with its Adler-32.
struct Part {
  std::unique_ptr<unsigned char[]> deflated;  // not zeroed: only the written bytes are touched
  size_t size = 0;
  uLong adler = 1;
  size_t raw_size = 0;
  bool ok = false;
};

void deflate_rows(const Image& image, int y0, int y1, bool last, Part& part) noexcept try {
  const size_t row_bytes = static_cast<size_t>(image.width) * 3;
  part.raw_size = (row_bytes + 1) * static_cast<size_t>(y1 - y0);
  z_stream zs{};
  // Level 1: several times faster than the default level, about 30% larger files.
  if (deflateInit2(&zs, 1, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK) return;
  const size_t capacity = deflateBound(&zs, static_cast<uLong>(part.raw_size)) + 16;
  part.deflated = std::make_unique_for_overwrite<unsigned char[]>(capacity);
  zs.next_out = part.deflated.get();
  zs.avail_out = static_cast<uInt>(capacity);
  // Each scanline is its filter byte, then the row: fed to zlib piece by piece, no copy.
  static const unsigned char kFilterNone = 0;
  part.ok = true;
  for (int y = y0; y < y1 && part.ok; ++y) {
    zs.next_in = const_cast<unsigned char*>(&kFilterNone);
    zs.avail_in = 1;
    part.ok = deflate(&zs, Z_NO_FLUSH) == Z_OK && zs.avail_in == 0;
    zs.next_in = const_cast<unsigned char*>(image.pixel(0, y));
    zs.avail_in = static_cast<uInt>(row_bytes);
    part.ok = part.ok && deflate(&zs, Z_NO_FLUSH) == Z_OK && zs.avail_in == 0;
    part.adler = adler32_z(adler32(part.adler, &kFilterNone, 1), image.pixel(0, y), row_bytes);
  }
  // A part other than the last ends with a sync flush (an empty stored block): byte-aligned
  // and not final, so the parts concatenate into one deflate stream. Each part starts a
  // fresh stream, so none refers back to the data of another.
  if (part.ok) {
    const int status = deflate(&zs, last ? Z_FINISH : Z_SYNC_FLUSH);
    part.ok = last ? status == Z_STREAM_END : status == Z_OK;
  }
  part.size = zs.total_out;
  deflateEnd(&zs);
} catch (const std::bad_alloc&) {
  part.ok = false;  // reported by the caller
}

}  // namespace

void Image::set_linear(int x, int y, const Color& c) {
  std::uint8_t* p = pixel(x, y);
  for (int k = 0; k < 3; ++k) {
    const double v = std::clamp(c[k], 0.0, 1.0);
    p[k] = static_cast<std::uint8_t>(std::lround(std::pow(v, 1.0 / 2.2) * 255.0));
  }
}

std::vector<std::uint8_t> encode_png(const Image& image) {
  if (image.width <= 0 || image.height <= 0)
    throw InvalidArgument("image", "empty", "no pixels to encode");
  // Compress bands of rows in parallel (as pigz does) and join them into one zlib stream.
  const size_t bytes = (static_cast<size_t>(image.width) * 3 + 1) * image.height;
  const size_t cores = std::max(1u, std::thread::hardware_concurrency());
  const int parts = static_cast<int>(
      std::clamp<size_t>(bytes / kMinPartBytes, 1, std::min<size_t>(cores, image.height)));
  std::vector<Part> part(static_cast<size_t>(parts));
  auto first_row = [&](int i) {
    return static_cast<int>(static_cast<long long>(image.height) * i / parts);
  };
  auto compress = [&](int i) {
    deflate_rows(image, first_row(i), first_row(i + 1), i + 1 == parts,
                 part[static_cast<size_t>(i)]);
  };
  {
    std::vector<std::jthread> workers;
    for (int i = 1; i < parts; ++i) workers.emplace_back(compress, i);
    compress(0);
  }
  std::vector<unsigned char> idat{0x78, 0x01};  // zlib header: deflate, 32K window, fastest
  uLong adler = part[0].adler;
  for (size_t i = 0; i < part.size(); ++i) {
    if (!part[i].ok) throw Error("PNG compression failed (out of memory?)");
    if (i > 0)
      adler = adler32_combine(adler, part[i].adler, static_cast<z_off_t>(part[i].raw_size));
    idat.insert(idat.end(), part[i].deflated.get(), part[i].deflated.get() + part[i].size);
  }
  append_u32(idat, static_cast<std::uint32_t>(adler));

  std::vector<unsigned char> header;
  append_u32(header, static_cast<std::uint32_t>(image.width));
  append_u32(header, static_cast<std::uint32_t>(image.height));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8-bit RGB, deflate, filters 0, no interlace
  std::ostringstream out;
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  out.write(reinterpret_cast<const char*>(kSignature), sizeof kSignature);
  write_chunk(out, "IHDR", header.data(), header.size());
  write_chunk(out, "IDAT", idat.data(), idat.size());
  write_chunk(out, "IEND", nullptr, 0);
  const std::string png = std::move(out).str();
  return {png.begin(), png.end()};
}

void write_png(const Image& image, const std::string& path) {
  if (image.width <= 0 || image.height <= 0) throw IoError(path, "image is empty");
  std::vector<unsigned char> bytes;
  try {
    bytes = encode_png(image);
  } catch (const Error& e) {
    throw WriteError(path, e.what());
  }
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  });
}

void write_ppm(const Image& image, const std::string& path) {
  if (image.width <= 0 || image.height <= 0) throw IoError(path, "image is empty");
  const std::string header =
      "P6\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    out.write(reinterpret_cast<const char*>(image.rgb.data()),
              static_cast<std::streamsize>(image.rgb.size()));
  });
}

const std::vector<std::string>& image_file_extensions() {
  static const std::vector<std::string> extensions = {"png", "ppm"};
  return extensions;
}

void write_image(const Image& image, const std::string& path) {
  const std::string ext = file_extension(path);
  if (ext == "png") return write_png(image, path);
  if (ext == "ppm") return write_ppm(image, path);
  throw InvalidArgument("picture file", path, "the name must end in .png or .ppm");
}

Image read_image(const std::string& path) {
  const std::string bytes = read_text_file(path);
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                                              static_cast<int>(bytes.size()), &w, &h, &n, 3);
  if (!data)
    throw IoError(path, std::string("not a readable PNG or PPM: ") + stbi_failure_reason());
  Image img(w, h);
  std::copy(data, data + static_cast<size_t>(w) * h * 3, img.rgb.begin());
  stbi_image_free(data);
  return img;
}

}  // namespace zeroset
