# All third-party dependencies of tactus, from Debian 12 packages. Each one missing stops the
# configure step with the package that provides it, instead of a cryptic CMake trace.
include_guard(GLOBAL)

macro(tactus_require name debian_package)
  if(NOT ${name}_FOUND)
    message(FATAL_ERROR
      "tactus needs ${name}, which was not found. On Debian 12 install it with:\n"
      "  apt-get install ${debian_package}\n"
      "(or run scripts/setup.sh, which installs every dependency).")
  endif()
endmacro()

find_package(Eigen3 3.3 QUIET NO_MODULE)
tactus_require(Eigen3 libeigen3-dev)

if(TACTUS_DEPENDENCIES_FOR_CONSUMER AND DEFINED TACTUS_HDF5_LIBRARIES)
  # An installed tactus records the HDF5 it was built with (FindHDF5 would need the consumer
  # project to enable the C language).
  set(HDF5_FOUND TRUE)
  set(HDF5_C_LIBRARIES "${TACTUS_HDF5_LIBRARIES}")
  set(HDF5_C_INCLUDE_DIRS "${TACTUS_HDF5_INCLUDE_DIRS}")
  set(HDF5_C_DEFINITIONS "")
else()
  find_package(HDF5 QUIET COMPONENTS C)
endif()
tactus_require(HDF5 libhdf5-dev)
if(NOT TARGET tactus_hdf5)
  add_library(tactus_hdf5 INTERFACE IMPORTED)
  set_target_properties(tactus_hdf5 PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${HDF5_C_INCLUDE_DIRS}"
    INTERFACE_LINK_LIBRARIES "${HDF5_C_LIBRARIES}"
    INTERFACE_COMPILE_DEFINITIONS "${HDF5_C_DEFINITIONS}")
endif()

# METIS 5 partitions the solver's atoms among ranks (solver/decomposition.hpp).
find_path(METIS_INCLUDE_DIR metis.h)
find_library(METIS_LIBRARY metis)
if(METIS_INCLUDE_DIR AND METIS_LIBRARY)
  set(METIS_FOUND TRUE)
endif()
tactus_require(METIS libmetis-dev)
if(NOT TARGET tactus_metis)
  add_library(tactus_metis INTERFACE IMPORTED)
  set_target_properties(tactus_metis PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${METIS_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${METIS_LIBRARY}")
endif()

find_path(GMSH_INCLUDE_DIR gmsh.h)
find_library(GMSH_LIBRARY gmsh)
if(GMSH_INCLUDE_DIR AND GMSH_LIBRARY)
  set(gmsh_FOUND TRUE)
endif()
tactus_require(gmsh libgmsh-dev)
if(NOT TARGET tactus_gmsh)
  add_library(tactus_gmsh INTERFACE IMPORTED)
  set_target_properties(tactus_gmsh PROPERTIES
    INTERFACE_INCLUDE_DIRECTORIES "${GMSH_INCLUDE_DIR}"
    INTERFACE_LINK_LIBRARIES "${GMSH_LIBRARY}")
endif()

find_package(VTK 9.1 QUIET COMPONENTS CommonCore CommonDataModel IOXML FiltersCore FiltersGeneral FiltersGeometry
  FiltersSources IOGeometry IOImage RenderingCore RenderingOpenGL2 RenderingFreeType RenderingAnnotation
  ChartsCore ViewsContext2D RenderingContext2D RenderingContextOpenGL2 InteractionStyle)
tactus_require(VTK libvtk9-dev)

find_package(nlohmann_json 3.10 QUIET)
tactus_require(nlohmann_json nlohmann-json3-dev)

find_package(tomlplusplus 3 QUIET)
tactus_require(tomlplusplus libtomlplusplus-dev)

find_package(OpenMP QUIET COMPONENTS CXX)
tactus_require(OpenMP "g++ (libgomp)")

if(NOT TACTUS_DEPENDENCIES_FOR_CONSUMER)
  # Build-only dependencies (header-only CLI parser, and the libraries of stages whose
  # executables need them at build time).
  find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp)
  if(CLI11_INCLUDE_DIR)
    set(CLI11_FOUND TRUE)
  endif()
  tactus_require(CLI11 libcli11-dev)

  find_package(CGAL 5.5 QUIET COMPONENTS ImageIO)
  tactus_require(CGAL libcgal-dev)

  find_package(OpenCV 4.6 QUIET COMPONENTS core imgproc imgcodecs)
  tactus_require(OpenCV libopencv-dev)

  # DICOM: GDCM decodes (and the phantom writes) pixel data; tactus walks every file first.
  find_package(GDCM 3 QUIET)
  tactus_require(GDCM libgdcm-dev)
  find_package(ZLIB QUIET)  # gzip-compressed NIfTI, NRRD and MetaImage voxels
  tactus_require(ZLIB zlib1g-dev)
endif()
