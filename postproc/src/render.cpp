// The report's pictures, rendered off screen with VTK: von Mises on the deformed bodies, a section
// through the hand, the skin pressure map with its peak, and time plots of the history.
#include "tactus/postproc/render.hpp"

#include <vtkActor.h>
#include <vtkAxis.h>
#include <vtkCamera.h>
#include <vtkCellData.h>
#include <vtkChartXY.h>
#include <vtkContextActor.h>
#include <vtkContextScene.h>
#include <vtkCutter.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlane.h>
#include <vtkPlot.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSphereSource.h>
#include <vtkTable.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkThreshold.h>
#include <vtkUnstructuredGrid.h>
#include <vtkWindowToImageFilter.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "tactus/core/error.hpp"
#include "tactus/core/log.hpp"

namespace fs = std::filesystem;

namespace tactus::postproc {

namespace {

vtkSmartPointer<vtkUnstructuredGrid> load(const fs::path& file) {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName(file.string().c_str());
  reader->Update();
  vtkSmartPointer<vtkUnstructuredGrid> g = reader->GetOutput();
  if (!g || g->GetNumberOfCells() == 0) throw InputError(file.string(), "", "a tactus-solve state (.vtu)", "no cells");
  return g;
}

// Cells of one body (cell field "body" == index), or everything when the field is absent.
vtkSmartPointer<vtkUnstructuredGrid> body_cells(vtkUnstructuredGrid* g, int body) {
  if (!g->GetCellData()->GetArray("body")) return g;
  vtkNew<vtkThreshold> t;
  t->SetInputData(g);
  t->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_CELLS, "body");
  t->SetLowerThreshold(body - 0.5);
  t->SetUpperThreshold(body + 0.5);
  t->SetThresholdFunction(vtkThreshold::THRESHOLD_BETWEEN);
  t->Update();
  return vtkSmartPointer<vtkUnstructuredGrid>(t->GetOutput());
}

vtkSmartPointer<vtkPolyData> surface(vtkDataSet* g) {
  vtkNew<vtkDataSetSurfaceFilter> s;
  s->SetInputData(g);
  s->Update();
  return vtkSmartPointer<vtkPolyData>(s->GetOutput());
}

vtkSmartPointer<vtkLookupTable> rainbow(double lo, double hi, bool log_scale) {
  auto lut = vtkSmartPointer<vtkLookupTable>::New();
  lut->SetHueRange(0.667, 0.0);
  lut->SetNumberOfTableValues(256);
  if (log_scale) lut->SetScaleToLog10();
  lut->SetTableRange(lo, hi);
  lut->SetBelowRangeColor(0.0, 0.0, 0.55, 1.0);
  lut->UseBelowRangeColorOn();
  lut->Build();
  return lut;
}

vtkSmartPointer<vtkActor> colored(vtkPolyData* poly, const char* array, bool cell_data, vtkLookupTable* lut) {
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(poly);
  mapper->SetLookupTable(lut);
  mapper->UseLookupTableScalarRangeOn();
  if (cell_data)
    mapper->SetScalarModeToUseCellFieldData();
  else
    mapper->SetScalarModeToUsePointFieldData();
  mapper->SelectColorArray(array);
  mapper->ScalarVisibilityOn();
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  return actor;
}

void add_scalar_bar(vtkRenderer* r, vtkLookupTable* lut, const std::string& title) {
  vtkNew<vtkScalarBarActor> bar;
  bar->SetLookupTable(lut);
  bar->SetTitle(title.c_str());
  bar->SetNumberOfLabels(5);
  bar->SetLabelFormat("%-#6.3g");
  bar->SetPosition(0.88, 0.1);
  bar->SetWidth(0.1);
  bar->SetHeight(0.8);
  bar->GetTitleTextProperty()->SetColor(0, 0, 0);
  bar->GetLabelTextProperty()->SetColor(0, 0, 0);
  r->AddActor2D(bar);
}

void add_text(vtkRenderer* r, const std::string& text, double x, double y, int size = 20) {
  vtkNew<vtkTextActor> t;
  t->SetInput(text.c_str());
  t->GetTextProperty()->SetFontSize(size);
  t->GetTextProperty()->SetColor(0, 0, 0);
  t->SetPosition(x, y);
  r->AddActor2D(t);
}

void write_png(vtkRenderWindow* window, const fs::path& file) {
  window->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(window);
  grab->ReadFrontBufferOff();
  grab->Update();
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(file.string().c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  if (!fs::exists(file)) throw InputError(file.string(), "", "a writable report folder", "PNG not written");
}

vtkSmartPointer<vtkRenderWindow> offscreen(int w, int h) {
  auto window = vtkSmartPointer<vtkRenderWindow>::New();
  window->SetOffScreenRendering(1);
  window->SetSize(w, h);
  return window;
}

vtkSmartPointer<vtkRenderer> white_renderer() {
  auto r = vtkSmartPointer<vtkRenderer>::New();
  r->SetBackground(1, 1, 1);
  return r;
}

// Camera on `direction` from the centre of `bounds`, z up (or y up when looking along z).
void look(vtkRenderer* r, const double* bounds, const std::array<double, 3>& direction, double zoom) {
  const double c[3] = {0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 0.5 * (bounds[4] + bounds[5])};
  vtkCamera* cam = r->GetActiveCamera();
  cam->SetFocalPoint(c);
  cam->SetPosition(c[0] + direction[0], c[1] + direction[1], c[2] + direction[2]);
  const double len = std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
  const bool along_z = std::abs(direction[2]) > 0.9 * len;
  cam->SetViewUp(0, along_z ? 1 : 0, along_z ? 0 : 1);
  r->ResetCamera(const_cast<double*>(bounds));
  cam->Zoom(zoom);
}

std::string ms(double t) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(2) << t * 1e3;
  return o.str();
}

std::size_t nearest_frame(const Results& r, double t) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < r.frames.size(); ++k)
    if (std::abs(r.frames[k].time - t) < std::abs(r.frames[best].time - t)) best = k;
  return best;
}

int body_index(const Results& r, const std::string& name, int fallback) {
  for (std::size_t b = 0; b < r.bodies.size(); ++b)
    if (r.bodies[b] == name) return static_cast<int>(b);
  return fallback;
}

void plot(const History& h, const fs::path& file, const std::string& title, const std::string& ylabel,
          const std::vector<std::pair<std::string, double>>& series, int w, int hgt) {
  if (!h.has("time")) return;
  vtkNew<vtkTable> table;
  vtkNew<vtkDoubleArray> t;
  t->SetName("time (ms)");
  table->AddColumn(t);
  std::vector<std::string> present;
  for (const auto& [name, scale] : series)
    if (h.has(name)) {
      vtkNew<vtkDoubleArray> a;
      a->SetName(name.c_str());
      table->AddColumn(a);
      present.push_back(name);
    }
  if (present.empty()) return;
  const auto& time = h.column("time");
  table->SetNumberOfRows(static_cast<vtkIdType>(time.size()));
  for (std::size_t i = 0; i < time.size(); ++i) {
    table->SetValue(static_cast<vtkIdType>(i), 0, time[i] * 1e3);
    int col = 1;
    for (const auto& [name, scale] : series)
      if (h.has(name)) table->SetValue(static_cast<vtkIdType>(i), col++, h.column(name)[i] * scale);
  }
  // The chart drawn by a context actor in a plain off-screen window: a vtkContextView would bring
  // an X interactor, which crashes when the X server is busy (seen with concurrent runs).
  auto window = offscreen(w, hgt);
  auto ren = white_renderer();
  window->AddRenderer(ren);
  vtkNew<vtkContextActor> actor;
  ren->AddActor(actor);
  vtkNew<vtkChartXY> chart;
  actor->GetScene()->AddItem(chart);
  chart->SetTitle(title);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle("time (ms)");
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(ylabel);
  chart->SetShowLegend(present.size() > 1);
  const unsigned char colors[5][3] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {148, 103, 189}, {255, 127, 14}};
  for (std::size_t k = 0; k < present.size(); ++k) {
    vtkPlot* line = chart->AddPlot(vtkChart::LINE);
    line->SetInputData(table, 0, static_cast<vtkIdType>(k + 1));
    line->SetColor(colors[k % 5][0], colors[k % 5][1], colors[k % 5][2], 255);
    line->SetWidth(2.0);
  }
  write_png(window, file);
}

}  // namespace

std::vector<std::string> render_report(const Results& r, const Summary& s, const fs::path& report, const RenderOptions& opt) {
  std::vector<std::string> written;
  if (r.frames.empty()) {
    log::warn("no output states in " + r.folder.string() + ": no pictures of the fields");
  } else {
    std::vector<std::size_t> chosen;
    if (opt.times.empty())
      for (std::size_t k = 0; k < r.frames.size(); ++k) chosen.push_back(k);
    else
      for (double t : opt.times) chosen.push_back(nearest_frame(r, t));
    std::sort(chosen.begin(), chosen.end());
    chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());

    // One fixed, logarithmic colour scale over every chosen state: soft tissue (kPa) and bone
    // (MPa) differ by orders of magnitude, and the spreading from the contact shows on a log scale.
    double vm_max = 0;
    for (const auto& m : s.von_mises) vm_max = std::max(vm_max, m.von_mises.value);
    if (!(vm_max > 0)) vm_max = 1;
    auto vm_lut = rainbow(vm_max * 1e-4, vm_max, true);
    // The view of the first state frames them all (bodies move little over a run).
    double bounds[6];
    const auto first = load(r.frames[chosen.front()].file);
    first->GetBounds(bounds);
    const double span = std::max({bounds[1] - bounds[0], bounds[3] - bounds[2], bounds[5] - bounds[4]});
    for (std::size_t k : chosen) {
      const auto g = load(r.frames[k].file);
      auto window = offscreen(opt.width, opt.height);
      auto ren = white_renderer();
      window->AddRenderer(ren);
      ren->AddActor(colored(surface(g), "von_mises", true, vm_lut));
      add_scalar_bar(ren, vm_lut, "von Mises (Pa)");
      add_text(ren, "t = " + ms(r.frames[k].time) + " ms   von Mises stress on the deformed bodies (log scale)", 20, opt.height - 40);
      look(ren, bounds, {0, -2 * span, 0}, 1.3);
      const std::string name = "von_mises_t" + ms(r.frames[k].time) + "ms.png";
      write_png(window, report / name);
      written.push_back(name);
    }

    // Section through the hand, normal to its long axis (z), at the peak pressure of the outputs
    // (or mid-height): bone, soft tissue and block, with their stress.
    {
      const std::size_t k = s.contact_occurred ? nearest_frame(r, s.peak_pressure_outputs.time) : r.frames.size() - 1;
      const auto g = load(r.frames[k].file);
      double b[6];
      g->GetBounds(b);
      const double z = s.contact_occurred && s.peak_pressure_outputs.index > 0 ? s.peak_pressure_outputs.position[2] : 0.5 * (b[4] + b[5]);
      vtkNew<vtkPlane> plane;
      plane->SetOrigin(0, 0, z);
      plane->SetNormal(0, 0, 1);
      vtkNew<vtkCutter> cut;
      cut->SetInputData(g);
      cut->SetCutFunction(plane);
      cut->Update();
      vtkPolyData* section = cut->GetOutput();
      if (section->GetNumberOfCells() > 0) {
        auto window = offscreen(opt.width * 2, opt.height);
        const double nm = std::max<double>(1, static_cast<double>(r.materials.size()) - 1);
        auto mat_lut = rainbow(0, nm, false);
        mat_lut->SetHueRange(0.1, 0.75);
        mat_lut->SetNumberOfTableValues(static_cast<vtkIdType>(nm + 1));
        mat_lut->Build();
        double sb[6];
        section->GetBounds(sb);
        for (int side = 0; side < 2; ++side) {
          auto ren = white_renderer();
          ren->SetViewport(0.5 * side, 0, 0.5 * side + 0.5, 1);
          window->AddRenderer(ren);
          if (side == 0) {
            ren->AddActor(colored(section, "material", true, mat_lut));
            std::string legend = "materials:";
            for (std::size_t m = 0; m < r.materials.size(); ++m) legend += "  " + std::to_string(m) + " " + r.materials[m];
            add_text(ren, legend, 20, 20, 18);
            add_scalar_bar(ren, mat_lut, "material");
          } else {
            ren->AddActor(colored(section, "von_mises", true, vm_lut));
            add_scalar_bar(ren, vm_lut, "von Mises (Pa)");
          }
          add_text(ren, "section z = " + ms(z) + " mm, t = " + ms(r.frames[k].time) + " ms", 20, opt.height - 40);
          look(ren, sb, {0, 0, 2 * span}, 1.2);
        }
        write_png(window, report / "section.png");
        written.push_back("section.png");
      }
    }

    // Contact pressure on the skin (the hand seen from the block), peak marked.
    if (s.contact_occurred && s.peak_pressure_outputs.value > 0) {
      const std::size_t k = nearest_frame(r, s.peak_pressure_outputs.time);
      const auto g = load(r.frames[k].file);
      const auto hand = surface(body_cells(g, body_index(r, "hand", 0)));
      double hb[6];
      hand->GetBounds(hb);
      auto window = offscreen(opt.width, opt.height);
      auto ren = white_renderer();
      window->AddRenderer(ren);
      auto p_lut = rainbow(0, s.peak_pressure_outputs.value, false);
      p_lut->SetBelowRangeColor(0.85, 0.85, 0.85, 1.0);
      p_lut->SetTableRange(1e-9 * s.peak_pressure_outputs.value, s.peak_pressure_outputs.value);
      ren->AddActor(colored(hand, "contact_pressure", false, p_lut));
      vtkNew<vtkSphereSource> marker;
      marker->SetCenter(s.peak_pressure_outputs.position.data());
      marker->SetRadius(0.012 * span);
      vtkNew<vtkPolyDataMapper> mm;
      mm->SetInputConnection(marker->GetOutputPort());
      vtkNew<vtkActor> ma;
      ma->SetMapper(mm);
      ma->GetProperty()->SetColor(0, 0, 0);
      ren->AddActor(ma);
      add_scalar_bar(ren, p_lut, "contact pressure (Pa)");
      std::ostringstream caption;
      caption << std::setprecision(3) << "t = " << ms(r.frames[k].time) << " ms   contact pressure on the skin; peak "
              << s.peak_pressure_outputs.value / 1e6 << " MPa (black dot) at (" << ms(s.peak_pressure_outputs.position[0]) << ", "
              << ms(s.peak_pressure_outputs.position[1]) << ", " << ms(s.peak_pressure_outputs.position[2]) << ") mm";
      add_text(ren, caption.str(), 20, opt.height - 40, 18);
      // From the block's side (+x: the direction of travel), so the contact patch faces the viewer.
      look(ren, hb, {2 * span, 0, 0}, 1.2);
      write_png(window, report / "pressure.png");
      written.push_back("pressure.png");
    }
  }

  const History& h = r.history;
  const int pw = 900, ph = 600;
  plot(h, report / "plot_contact_force.png", "total contact force", "N", {{"contact_force", 1.0}}, pw, ph);
  plot(h, report / "plot_contact_area.png", "contact area", "mm^2", {{"contact_area", 1e6}}, pw, ph);
  plot(h, report / "plot_peak_pressure.png", "peak contact pressure", "MPa", {{"peak_pressure", 1e-6}}, pw, ph);
  plot(h, report / "plot_energies.png", "energies", "J",
       {{"kinetic_energy", 1.0}, {"internal_energy", 1.0}, {"contact_work_normal", 1.0}, {"contact_work_friction", 1.0},
        {"energy_balance_error", 1.0}},
       pw, ph);
  for (const char* f : {"plot_contact_force.png", "plot_contact_area.png", "plot_peak_pressure.png", "plot_energies.png"})
    if (fs::exists(report / f)) written.push_back(f);
  return written;
}

}  // namespace tactus::postproc
