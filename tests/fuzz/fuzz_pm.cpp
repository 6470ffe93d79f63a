// libFuzzer target: a .pm stream's bytes. Reading must return what survives or throw lodkit::Error;
// the levels it returns must extract, and geomorph, without a crash or a sanitizer report.
#include <lodkit/error.h>
#include <lodkit/pm_io.h>
#include <lodkit/progressive.h>

#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lodkit;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  try {
    const PmReadResult r = read_pm_from_memory(bytes, "fuzz input");
    const ProgressiveMesh& pm = r.pm;
    const Index n = static_cast<Index>(pm.splits.size());
    if (pm.base_faces + 2 * static_cast<long long>(n) > 20000) return 0;  // keep each run short
    (void)extract_level(pm, 0);
    (void)extract_level(pm, n / 2);
    (void)extract_level(pm, n);
    if (n > 0) (void)make_geomorph(pm, 0, n);
  } catch (const Error&) {
  }
  return 0;
}
