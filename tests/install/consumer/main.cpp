#include <lodkit/inspect.h>
#include <lodkit/io.h>
#include <lodkit/primitives.h>
#include <lodkit/version.h>

#include <cstdio>

int main() {
  const lodkit::Mesh torus = lodkit::make_torus({.tolerance = 0.01});
  const std::string bytes = lodkit::write_mesh_to_memory(torus, lodkit::MeshFormat::Draco);
  const lodkit::Mesh back = lodkit::read_mesh_from_memory(bytes, lodkit::MeshFormat::Draco, "mem.drc");
  const lodkit::MeshReport r = lodkit::inspect(back);
  std::printf("lodkit %s: %d faces, genus %lld\n", LODKIT_VERSION_STRING, back.num_faces(), r.genus.value_or(-1));
  return r.closed && r.genus == 1 ? 0 : 1;
}
