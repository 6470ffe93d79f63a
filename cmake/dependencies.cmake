# Every dependency comes from a Debian 12 package (scripts/install-deps.sh installs them).
find_package(Eigen3 3.3 REQUIRED NO_MODULE)  # NO_MODULE: CGAL ships a FindEigen3 that would shadow the target
find_package(fmt REQUIRED)
find_package(draco REQUIRED)
find_package(ZLIB REQUIRED)            # CRC-32 of .pm blocks
find_package(TBB REQUIRED)
find_package(Threads REQUIRED)
find_package(CGAL REQUIRED)           # booleans (lib/src/csg/boolean.cpp only)
find_package(nlohmann_json 3 REQUIRED)
# OpenSubdiv: Debian's OpenSubdivConfig lists static libraries it does not ship, so find the shared
# CPU library and the headers directly.
find_library(LODKIT_OSD_CPU osdCPU REQUIRED)
find_path(LODKIT_OSD_INCLUDE opensubdiv/far/topologyRefiner.h REQUIRED)
if(LODKIT_BUILD_CLI)
  find_package(CLI11 REQUIRED)
endif()
