// libFuzzer target: a CSG tree's JSON. Parsing must return a tree or throw lodkit::Error. With
// LODKIT_FUZZ_DEEP set, a tree of at most four primitives is also evaluated (coarse tolerance): a
// result or lodkit::Error, never a crash, and no primitive so fine it exhausts memory.
#include <lodkit/csg.h>
#include <lodkit/error.h>

#include <cstdint>
#include <cstdlib>
#include <string>

namespace {

int count_primitives(const lodkit::CsgNode& node) {
  int n = node.kind == lodkit::CsgNode::Kind::Operation ? 0 : 1;
  for (const lodkit::CsgNode& child : node.children) n += count_primitives(child);
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lodkit;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // Mesh files are resolved against a directory that does not exist: reading one is an Error.
    const CsgNode tree = parse_csg(text, "fuzz input", "/nonexistent-lodkit-fuzz");
    static const bool deep = std::getenv("LODKIT_FUZZ_DEEP") != nullptr;
    if (deep && count_primitives(tree) <= 4) {
      CsgOptions options;
      options.tolerance = 0.2;
      (void)evaluate(tree, options);
    }
  } catch (const Error&) {
  }
  return 0;
}
