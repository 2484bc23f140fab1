// One fuzz harness: `fuzzOne` runs one input through the code under test and returns a one-line
// outcome ("ok: ..." or "error: <the message a user would see>"); it returns for every input and
// aborts only when an invariant of the output is broken. The same source builds two ways:
//   - with clang and -fsanitize=fuzzer,address,undefined (fuzz/run_fuzzers.sh): libFuzzer calls
//     LLVMFuzzerTestOneInput below;
//   - with the normal build (gcc, no sanitizer): replay_main.cpp calls fuzzOne on files given on
//     the command line (the committed corpora and the findings, as ctests).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace freeinit::fuzz {

std::string fuzzOne(const std::uint8_t* data, std::size_t size);

/// A broken invariant: a bug even when no sanitizer sees it.
[[noreturn]] inline void broken(const char* what) {
  std::fprintf(stderr, "invariant broken: %s\n", what);
  std::abort();
}

/// Writes the input to a file of this process ("freeinit_fuzz_<stem>_<pid><ext>" in the temporary
/// folder) for the readers that take a path; returns its path, or "" (with `error`) on failure.
inline std::string writeInput(const char* stem, const char* ext, const std::uint8_t* data,
                              std::size_t size, std::string& error) {
  const std::string path =
      (std::filesystem::temp_directory_path() /
       ("freeinit_fuzz_" + std::string(stem) + "_" + std::to_string(getpid()) + ext))
          .string();
  FILE* f = std::fopen(path.c_str(), "wb");
  const bool ok = f != nullptr && std::fwrite(data, 1, size, f) == size;
  if (f != nullptr) std::fclose(f);
  if (!ok) error = "error: cannot write " + path;
  return ok ? path : std::string();
}

/// The first line of a message (outcomes are one line).
inline std::string firstLine(const std::string& s) { return s.substr(0, s.find('\n')); }

}  // namespace freeinit::fuzz

#ifdef FREEINIT_LIBFUZZER
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  freeinit::fuzz::fuzzOne(data, size);
  return 0;
}
#endif
