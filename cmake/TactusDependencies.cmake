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

# A plain C library (one header, one library file, no CMake package) as the imported target
# tactus_<target>; stops with the Debian package when missing.
macro(tactus_plain_library target header library debian_package)
  string(TOUPPER ${target} _upper)
  find_path(${_upper}_INCLUDE_DIR ${header})
  find_library(${_upper}_LIBRARY ${library})
  if(${_upper}_INCLUDE_DIR AND ${_upper}_LIBRARY)
    set(${target}_FOUND TRUE)
  endif()
  tactus_require(${target} ${debian_package})
  if(NOT TARGET tactus_${target})
    add_library(tactus_${target} INTERFACE IMPORTED)
    set_target_properties(tactus_${target} PROPERTIES
      INTERFACE_INCLUDE_DIRECTORIES "${${_upper}_INCLUDE_DIR}"
      INTERFACE_LINK_LIBRARIES "${${_upper}_LIBRARY}")
  endif()
endmacro()

# METIS 5 partitions the solver's atoms among ranks (solver/decomposition.hpp).
tactus_plain_library(metis metis.h metis libmetis-dev)
tactus_plain_library(gmsh gmsh.h gmsh libgmsh-dev)

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
