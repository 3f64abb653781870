// The entry point of a fuzz target when it is not built with libFuzzer (-fsanitize=fuzzer):
// runs the target once on every file named, or on every file of every directory named, in
// sorted order, so the committed corpus is a regression suite in every build. A violated
// property aborts inside the target; this program prints which input it was running first.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

// NOLINTNEXTLINE(readability-identifier-naming): the name libFuzzer calls.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

std::vector<std::filesystem::path> inputs(int argc, char** argv) {
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path arg = argv[i];  // NOLINT(*-pointer-arithmetic)
    if (std::filesystem::is_directory(arg)) {
      std::vector<std::filesystem::path> in_dir;
      for (const auto& entry : std::filesystem::directory_iterator(arg)) {
        if (entry.is_regular_file()) in_dir.push_back(entry.path());
      }
      std::sort(in_dir.begin(), in_dir.end());
      files.insert(files.end(), in_dir.begin(), in_dir.end());
    } else {
      files.push_back(arg);
    }
  }
  return files;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::filesystem::path> files = inputs(argc, argv);
  if (files.empty()) {
    static_cast<void>(std::fprintf(stderr,
                                   "usage: %s FILE|DIR...  (runs the fuzz target on each input)\n",
                                   argc > 0 ? argv[0] : "fuzz-replay"));
    return 2;
  }
  for (const std::filesystem::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    if (!in) {
      static_cast<void>(std::fprintf(stderr, "cannot read %s\n", file.c_str()));
      return 2;
    }
    const std::vector<char> bytes{std::istreambuf_iterator<char>(in),
                                  std::istreambuf_iterator<char>()};
    static_cast<void>(std::fprintf(stderr, "running %s (%zu bytes)\n", file.c_str(), bytes.size()));
    std::vector<std::uint8_t> data(bytes.begin(), bytes.end());
    LLVMFuzzerTestOneInput(data.data(), data.size());
  }
  std::printf("%zu inputs, all properties held\n", files.size());
  return 0;
}
