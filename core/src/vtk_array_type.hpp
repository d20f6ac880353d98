#pragma once
// Maps a C++ voxel/field type to the VTK array class that stores it without conversion.
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkShortArray.h>
#include <vtkSmartPointer.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnsignedShortArray.h>

#include <cstdint>

namespace tactus {

template <class T>
auto make_vtk_array() {
  if constexpr (std::is_same_v<T, std::uint8_t>)
    return vtkSmartPointer<vtkUnsignedCharArray>::New();
  else if constexpr (std::is_same_v<T, std::uint16_t>)
    return vtkSmartPointer<vtkUnsignedShortArray>::New();
  else if constexpr (std::is_same_v<T, std::int16_t>)
    return vtkSmartPointer<vtkShortArray>::New();
  else if constexpr (std::is_same_v<T, std::int32_t>)
    return vtkSmartPointer<vtkIntArray>::New();
  else if constexpr (std::is_same_v<T, float>)
    return vtkSmartPointer<vtkFloatArray>::New();
  else
    return vtkSmartPointer<vtkDoubleArray>::New();
}

}  // namespace tactus
