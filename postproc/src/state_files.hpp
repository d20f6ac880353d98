#pragma once
// What the report's writers (render.cpp, web_report.cpp) share about the state files: reading one,
// and the time label their file names carry. Private to the postproc library.
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>

#include <filesystem>
#include <string>
#include <vector>

namespace tactus::postproc {

// A tactus-solve state (.vtu) read with VTK; InputError naming the file when it is not a regular
// file or has no cells.
vtkSmartPointer<vtkUnstructuredGrid> load_state(const std::filesystem::path& file);

// An output time as file names carry it: milliseconds with two decimals ("1.00").
std::string ms(double t);

// The tets' von Mises averaged at each point, weighted by the tets' current volumes: the nodal
// von Mises of the pictures and of the interactive report (0 at a point no tet holds; empty
// without a von_mises cell field).
std::vector<double> nodal_von_mises(vtkUnstructuredGrid* g);

}  // namespace tactus::postproc
