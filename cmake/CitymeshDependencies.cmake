# SPDX-License-Identifier: MIT
# Finds every third-party dependency once; each is used by exactly one wrapper source.
find_package(Threads REQUIRED)
find_package(TBB REQUIRED)
find_package(nanoflann REQUIRED)
find_package(embree 3 REQUIRED)
find_package(draco REQUIRED)
find_package(tomlplusplus REQUIRED)
find_package(CLI11 REQUIRED)
find_package(spdlog REQUIRED)
find_package(fmt REQUIRED)
find_package(nlohmann_json REQUIRED)
find_package(meshoptimizer REQUIRED)

# OpenVDB ships a Find module (not a config file) in its own cmake folder.
list(APPEND CMAKE_MODULE_PATH "/usr/lib/x86_64-linux-gnu/cmake/OpenVDB" "/usr/lib/cmake/OpenVDB")
find_package(OpenVDB REQUIRED)

# Debian installs GeographicLib's Find module outside CMake's default path.
list(APPEND CMAKE_MODULE_PATH "/usr/share/cmake/geographiclib")
find_package(GeographicLib REQUIRED)
if(NOT TARGET GeographicLib::GeographicLib)
  add_library(GeographicLib::GeographicLib INTERFACE IMPORTED)
  target_include_directories(GeographicLib::GeographicLib SYSTEM INTERFACE ${GeographicLib_INCLUDE_DIRS})
  target_link_libraries(GeographicLib::GeographicLib INTERFACE ${GeographicLib_LIBRARIES})
endif()

find_package(PkgConfig REQUIRED)
pkg_check_modules(HTTPLIB REQUIRED IMPORTED_TARGET cpp-httplib)
# xxHash (libxxhash-dev): the checksum of the bulk binary files (tile store, tile results).
pkg_check_modules(XXHASH REQUIRED IMPORTED_TARGET libxxhash)

# Optional: OpenMPI (libopenmpi-dev) for runs across machines; tools/setup installs it.
# Only the C API is used (cluster_mpi.cpp), through the C++ compiler wrapper's flags.
set(MPI_CXX_SKIP_MPICXX ON)
find_package(MPI COMPONENTS CXX)
if(NOT MPI_CXX_FOUND)
  message(STATUS "MPI not found: citymesh runs in one process (install libopenmpi-dev for mpirun)")
endif()
