// Replays inputs through a harness built without libFuzzer: each argument is a file or a folder
// (its files, sorted); prints "<file>: <outcome>" per input. Exit status 0 once every input ran
// (a crash or an abort of the harness is the failure), 2 for a missing argument.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <vector>

#include "harness.h"

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  if (argc < 2) {
    std::cerr << "usage: " << argv[0] << " FILE_OR_FOLDER...\n";
    return 2;
  }
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path p(argv[i]);
    if (fs::is_directory(p)) {
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
      inputs.insert(inputs.end(), files.begin(), files.end());
    } else if (fs::is_regular_file(p)) {
      inputs.push_back(p);
    } else {
      std::cerr << argv[0] << ": " << p.string() << ": no such file or folder\n";
      return 2;
    }
  }
  for (const auto& p : inputs) {
    std::ifstream in(p, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                  std::istreambuf_iterator<char>());
    std::cout << p.string() << ": "
              << freeinit::fuzz::fuzzOne(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                         bytes.size())
              << std::endl;
  }
  return 0;
}
