#pragma once
// The bad-input corpus: every way a mesh file can be broken that readers must refuse cleanly.
// Generated into a directory by the tests (library and CLI alike) so the corpus and the
// expectations live side by side.
#include <filesystem>
#include <string>
#include <vector>

namespace lodkit::test {

struct BadFile {
  std::string name;      ///< file name, with the extension that selects the reader
  std::string expected;  ///< a fragment the error message must contain
};

/// Writes the corpus into `dir` and returns its entries.
std::vector<BadFile> write_bad_corpus(const std::filesystem::path& dir);

}  // namespace lodkit::test
