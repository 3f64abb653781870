// Helper of the browser test (diagnose_report_browser.sh):
//   diagnose_report_browser write OUT.html SAMPLES   writes the sample report
//   diagnose_report_browser ink SHOT.png Y0 Y1       counts the pixels of rows Y0..Y1 that are
//                                                    not white, and those that are coloured
// The PNG reader covers what a browser screenshot is: 8-bit RGB or RGBA, not interlaced.
#include <zlib.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/report_sample.hpp"
#include "selfsense/report/diagnose_report.hpp"

namespace {

struct Image {
  std::size_t width{0};
  std::size_t height{0};
  std::size_t channels{0};
  std::vector<std::uint8_t> pixels;  // rows of width * channels bytes
};

std::uint32_t be32(const std::vector<std::uint8_t>& b, std::size_t at) {
  return (static_cast<std::uint32_t>(b[at]) << 24U) |
         (static_cast<std::uint32_t>(b[at + 1]) << 16U) |
         (static_cast<std::uint32_t>(b[at + 2]) << 8U) | static_cast<std::uint32_t>(b[at + 3]);
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a);
  const int pb = std::abs(p - b);
  const int pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

Image read_png(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot open " + path);
  const std::vector<std::uint8_t> b{std::istreambuf_iterator<char>(file),
                                    std::istreambuf_iterator<char>()};
  const std::uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (b.size() < 8 || !std::equal(std::begin(signature), std::end(signature), b.begin())) {
    throw std::runtime_error(path + ": not a PNG");
  }
  Image img;
  std::vector<std::uint8_t> compressed;
  std::size_t at = 8;
  while (at + 12 <= b.size()) {
    const std::size_t length = be32(b, at);
    const std::string type(b.begin() + static_cast<std::ptrdiff_t>(at + 4),
                           b.begin() + static_cast<std::ptrdiff_t>(at + 8));
    const std::size_t data = at + 8;
    if (data + length + 4 > b.size()) throw std::runtime_error(path + ": truncated chunk");
    if (type == "IHDR") {
      img.width = be32(b, data);
      img.height = be32(b, data + 4);
      const int depth = b[data + 8];
      const int colour = b[data + 9];
      const int interlace = b[data + 12];
      if (depth != 8 || (colour != 2 && colour != 6) || interlace != 0) {
        throw std::runtime_error(path + ": only 8-bit RGB(A), non-interlaced PNG is read");
      }
      img.channels = colour == 6 ? 4 : 3;
    } else if (type == "IDAT") {
      compressed.insert(compressed.end(), b.begin() + static_cast<std::ptrdiff_t>(data),
                        b.begin() + static_cast<std::ptrdiff_t>(data + length));
    } else if (type == "IEND") {
      break;
    }
    at = data + length + 4;
  }
  if (img.channels == 0) throw std::runtime_error(path + ": no IHDR");
  const std::size_t stride = img.width * img.channels;
  std::vector<std::uint8_t> raw(img.height * (stride + 1));
  uLongf raw_size = raw.size();
  if (uncompress(raw.data(), &raw_size, compressed.data(), compressed.size()) != Z_OK ||
      raw_size != raw.size()) {
    throw std::runtime_error(path + ": bad image data");
  }
  img.pixels.assign(img.height * stride, 0);
  for (std::size_t y = 0; y < img.height; ++y) {
    const std::uint8_t filter = raw[y * (stride + 1)];
    const std::uint8_t* in = &raw[y * (stride + 1) + 1];
    std::uint8_t* out = &img.pixels[y * stride];
    const std::uint8_t* up = y > 0 ? &img.pixels[(y - 1) * stride] : nullptr;
    for (std::size_t i = 0; i < stride; ++i) {
      const int a = i >= img.channels ? out[i - img.channels] : 0;
      const int u = up != nullptr ? up[i] : 0;
      const int c = (up != nullptr && i >= img.channels) ? up[i - img.channels] : 0;
      int predictor = 0;
      switch (filter) {
        case 0:
          break;
        case 1:
          predictor = a;
          break;
        case 2:
          predictor = u;
          break;
        case 3:
          predictor = (a + u) / 2;
          break;
        case 4:
          predictor = paeth(a, u, c);
          break;
        default:
          throw std::runtime_error(path + ": bad filter");
      }
      out[i] = static_cast<std::uint8_t>((in[i] + predictor) & 0xff);
    }
  }
  return img;
}

int ink(const std::string& path, std::size_t y0, std::size_t y1) {
  const Image img = read_png(path);
  y1 = std::min(y1, img.height);
  std::size_t dark = 0;
  std::size_t coloured = 0;
  std::size_t rows_with_ink = 0;
  for (std::size_t y = y0; y < y1; ++y) {
    bool row_ink = false;
    for (std::size_t x = 0; x < img.width; ++x) {
      const std::uint8_t* p = &img.pixels[(y * img.width + x) * img.channels];
      const int lo = std::min({p[0], p[1], p[2]});
      const int hi = std::max({p[0], p[1], p[2]});
      if (lo < 235) {
        ++dark;
        row_ink = true;
      }
      if (hi - lo > 60) ++coloured;
    }
    if (row_ink) ++rows_with_ink;
  }
  std::printf("width=%zu height=%zu rows=%zu ink=%zu coloured=%zu rows_with_ink=%zu\n", img.width,
              img.height, y1 > y0 ? y1 - y0 : 0, dark, coloured, rows_with_ink);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> args(argv + 1, argv + argc);
    if (args.size() == 3 && args[0] == "write") {
      selfsense::report::write_diagnosis_report(
          selfsense::test::make_sample_report(std::stoul(args[2])), args[1]);
      return 0;
    }
    if (args.size() == 4 && args[0] == "ink") {
      return ink(args[1], std::stoul(args[2]), std::stoul(args[3]));
    }
    (void)std::fprintf(
        stderr, "usage: diagnose_report_browser write OUT.html SAMPLES | ink SHOT.png Y0 Y1\n");
    return 2;
  } catch (const std::exception& e) {
    (void)std::fprintf(stderr, "diagnose_report_browser: %s\n", e.what());
    return 1;
  }
}
