#pragma once
// main() of a bench program whose arguments are mesh paths only: --help prints the usage, an option or
// no mesh is a usage error (2), and an exception from `run` is reported with the program's name (1).
#include <exception>
#include <fmt/format.h>
#include <string>

inline int mesh_list_main(int argc, char** argv, const char* name, const char* usage, int (*run)(int, char**)) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      fmt::print("{}", usage);
      return 0;
    }
    if (a.starts_with("-")) {
      fmt::print(stderr, "{}: unknown option {}\n{}", name, a, usage);
      return 2;
    }
  }
  if (argc < 2) {
    fmt::print(stderr, "{}", usage);
    return 2;
  }
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    fmt::print(stderr, "{}: {}\n", name, e.what());
    return 1;
  }
}
