// The report's pictures, rendered off screen with VTK: von Mises on the deformed bodies, a section
// through the hand, the skin pressure map with its peak, and time plots of the history.
#include "tactus/postproc/render.hpp"

#include <vtkActor.h>
#include <vtkActor2D.h>
#include <vtkAxesActor.h>
#include <vtkAxis.h>
#include <vtkCamera.h>
#include <vtkCaptionActor2D.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkChartXY.h>
#include <vtkContextActor.h>
#include <vtkContextScene.h>
#include <vtkCubeAxesActor.h>
#include <vtkCutter.h>
#include <vtkDataSetSurfaceFilter.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkLookupTable.h>
#include <vtkMath.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlane.h>
#include <vtkPlot.h>
#include <vtkPlotPoints.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkPolyDataMapper2D.h>
#include <vtkPolyDataNormals.h>
#include <vtkProperty.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkSphereSource.h>
#include <vtkTable.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkThreshold.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>
#include <vtkVariant.h>
#include <vtkWindowToImageFilter.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "state_files.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"

namespace fs = std::filesystem;

namespace tactus::postproc {

namespace cc = contracts::cell;
namespace cp = contracts::point;
namespace hc = contracts::history;

namespace {

// Cells of one body (cell field "body" == index), or everything when the field is absent.
vtkSmartPointer<vtkUnstructuredGrid> body_cells(vtkUnstructuredGrid* g, int body) {
  if (!g->GetCellData()->GetArray(cc::body.name)) return g;
  vtkNew<vtkThreshold> t;
  t->SetInputData(g);
  t->SetInputArrayToProcess(0, 0, 0, vtkDataObject::FIELD_ASSOCIATION_CELLS, cc::body.name);
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
  // Encoded in memory and written with every write checked (a full disk is an error, not a short PNG).
  vtkNew<vtkPNGWriter> writer;
  writer->WriteToMemoryOn();
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  vtkUnsignedCharArray* png = writer->GetResult();
  if (!png || png->GetNumberOfValues() == 0) throw WriteError(file.string(), "VTK did not encode the picture");
  write_file(file, std::string_view(reinterpret_cast<const char*>(png->GetPointer(0)), static_cast<std::size_t>(png->GetNumberOfValues())));
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

// The side a picture is seen from, in the model's axes: each axis whose component of the direction
// towards the camera is at least a third of it, signed ("+x", "-y +z").
std::string seen_from(const Vec3& to_camera) {
  const Vec3 d = (1.0 / norm(to_camera)) * to_camera;
  std::string side;
  for (int k = 0; k < 3; ++k)
    if (std::abs(d[k]) >= 1.0 / 3) side += std::string(side.empty() ? "" : " ") + (d[k] > 0 ? "+" : "-") + "xyz"[k];
  return "seen from " + side;
}

// A round length (1, 2 or 5 times a power of ten) at most `limit`.
double round_length(double limit) {
  const double decade = std::pow(10.0, std::floor(std::log10(limit)));
  for (double m : {5.0, 2.0, 1.0})
    if (m * decade <= limit) return m * decade;
  return decade;
}

// What every 3-D picture carries beside its colours, in the corner of renderer `ren` (already
// looking at the model through a parallel projection): an axes triad turned as the model is, the
// side it is seen from, and a scale bar of a round length in mm. The projection is parallel, so the
// bar holds everywhere in the picture, not only at one depth.
void add_view_keys(vtkRenderWindow* window, vtkRenderer* ren) {
  const int* size = window->GetSize();
  const double* vp = ren->GetViewport();
  const double w = (vp[2] - vp[0]) * size[0], h = (vp[3] - vp[1]) * size[1];
  vtkCamera* cam = ren->GetActiveCamera();
  // The triad: a small renderer on the layer above, its camera along the main one's.
  const double side = 0.16 * h;
  auto triad = vtkSmartPointer<vtkRenderer>::New();
  triad->SetViewport(vp[0], vp[1] + 0.08 * (vp[3] - vp[1]), vp[0] + side / size[0], vp[1] + 0.08 * (vp[3] - vp[1]) + side / size[1]);
  triad->SetLayer(1);
  triad->InteractiveOff();
  window->SetNumberOfLayers(2);
  window->AddRenderer(triad);
  vtkNew<vtkAxesActor> axes;
  axes->SetShaftTypeToCylinder();
  axes->SetCylinderRadius(0.04);
  axes->SetConeRadius(0.5);
  for (vtkCaptionActor2D* label : {axes->GetXAxisCaptionActor2D(), axes->GetYAxisCaptionActor2D(), axes->GetZAxisCaptionActor2D()}) {
    label->GetCaptionTextProperty()->SetColor(0, 0, 0);
    label->GetCaptionTextProperty()->ShadowOff();
    label->GetCaptionTextProperty()->ItalicOff();
  }
  triad->AddActor(axes);
  double dop[3];
  cam->GetDirectionOfProjection(dop);
  vtkCamera* tc = triad->GetActiveCamera();
  tc->SetFocalPoint(0, 0, 0);
  tc->SetPosition(-4 * dop[0], -4 * dop[1], -4 * dop[2]);
  tc->SetViewUp(cam->GetViewUp());
  triad->ResetCamera();
  add_text(ren, seen_from({-dop[0], -dop[1], -dop[2]}), 20, 0.08 * h + side + 4, 16);
  // The scale bar: parallel scale = half the viewport's height in metres.
  const double metres_per_pixel = 2 * cam->GetParallelScale() / h;
  const double length = round_length(0.2 * w * metres_per_pixel), pixels = length / metres_per_pixel;
  const double x0 = side + 40, y0 = 0.08 * h + 12;
  vtkNew<vtkPoints> pts;
  for (const auto& [x, y] : {std::pair{x0, y0}, {x0 + pixels, y0}, {x0, y0 - 6}, {x0, y0 + 6}, {x0 + pixels, y0 - 6}, {x0 + pixels, y0 + 6}})
    pts->InsertNextPoint(x, y, 0);
  vtkNew<vtkCellArray> lines;
  for (vtkIdType k = 0; k < 6; k += 2) {
    const vtkIdType ends[2] = {k, k + 1};
    lines->InsertNextCell(2, ends);
  }
  vtkNew<vtkPolyData> bar;
  bar->SetPoints(pts);
  bar->SetLines(lines);
  vtkNew<vtkPolyDataMapper2D> mapper;
  mapper->SetInputData(bar);
  vtkNew<vtkActor2D> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(0, 0, 0);
  actor->GetProperty()->SetLineWidth(2);
  ren->AddActor2D(actor);
  std::ostringstream label;
  label << 1e3 * length << " mm";
  add_text(ren, label.str(), x0, y0 + 10, 16);
}

// Camera on `direction` from the centre of `bounds`, `up` up (made perpendicular to the view),
// with a parallel projection (a scale bar holds at every depth).
void look(vtkRenderer* r, const double* bounds, const Vec3& direction, Vec3 up, double zoom) {
  const double c[3] = {0.5 * (bounds[0] + bounds[1]), 0.5 * (bounds[2] + bounds[3]), 0.5 * (bounds[4] + bounds[5])};
  const Vec3 d = (1.0 / norm(direction)) * direction;
  up = up - dot(up, d) * d;
  if (norm(up) < 1e-6) up = std::abs(d[2]) < 0.9 ? Vec3{0, 0, 1} : Vec3{0, 1, 0};
  vtkCamera* cam = r->GetActiveCamera();
  cam->SetFocalPoint(c);
  cam->SetPosition(c[0] + d[0], c[1] + d[1], c[2] + d[2]);
  cam->SetViewUp(up.data());
  cam->ParallelProjectionOn();
  r->ResetCamera(const_cast<double*>(bounds));
  cam->Zoom(zoom);
}

// Principal axes of a point set, by increasing extent (eigenvectors of the covariance), each
// signed so that its largest component is positive (a deterministic choice).
std::array<Vec3, 3> principal_axes(vtkPoints* points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  const vtkIdType n = points->GetNumberOfPoints();
  for (vtkIdType i = 0; i < n; ++i) mean += Eigen::Vector3d(points->GetPoint(i));
  mean /= std::max<double>(1, static_cast<double>(n));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (vtkIdType i = 0; i < n; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(points->GetPoint(i)) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);  // eigenvalues ascending
  std::array<Vec3, 3> axes;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d v = es.eigenvectors().col(k);
    Eigen::Index big;
    v.cwiseAbs().maxCoeff(&big);
    if (v[big] < 0) v = -v;
    axes[static_cast<std::size_t>(k)] = {v[0], v[1], v[2]};
  }
  return axes;
}

// The pressure-weighted outward normal of a body's surface where it is pressed: the side its
// contact faces.
Vec3 pressed_side(vtkPolyData* surface) {
  vtkNew<vtkPolyDataNormals> normals;
  normals->SetInputData(surface);
  normals->ComputePointNormalsOn();
  normals->AutoOrientNormalsOn();  // outward for a closed surface
  normals->SplittingOff();
  normals->Update();
  vtkPolyData* out = normals->GetOutput();
  vtkDataArray* n = out->GetPointData()->GetNormals();
  vtkDataArray* p = out->GetPointData()->GetArray(cp::contact_pressure.name);
  Vec3 sum{0, 0, 0};
  if (n && p)
    for (vtkIdType i = 0; i < out->GetNumberOfPoints(); ++i) {
      const double w = p->GetComponent(i, 0);
      if (w > 0) sum = sum + w * Vec3{n->GetComponent(i, 0), n->GetComponent(i, 1), n->GetComponent(i, 2)};
    }
  return norm(sum) > 0 ? sum : Vec3{1, 0, 0};
}

// A surface's contact pressure on a scale from 0 to `scale_max`, exactly 0 (no contact) grey, with
// its bar and a black dot of radius `marker_radius` at `peak`.
void add_pressure_map(vtkRenderer* ren, vtkPolyData* surface, double scale_max, const Vec3& peak, double marker_radius) {
  auto lut = rainbow(0, scale_max, false);
  lut->SetBelowRangeColor(0.85, 0.85, 0.85, 1.0);
  lut->SetTableRange(1e-9 * scale_max, scale_max);  // exactly 0 (no contact) is below the range: grey
  ren->AddActor(colored(surface, cp::contact_pressure.name, false, lut));
  vtkNew<vtkSphereSource> marker;
  marker->SetCenter(peak.data());
  marker->SetRadius(marker_radius);
  vtkNew<vtkPolyDataMapper> mm;
  mm->SetInputConnection(marker->GetOutputPort());
  vtkNew<vtkActor> ma;
  ma->SetMapper(mm);
  ma->GetProperty()->SetColor(0, 0, 0);
  ren->AddActor(ma);
  // The bar reads from 0 in MPa: the same colours, without the grey floor's offset in its labels.
  add_scalar_bar(ren, rainbow(0, 1e-6 * scale_max, false), "contact pressure (MPa)");
}

// The pressed nodes' (pressure, area) of `surfaces` pooled (a node's area: a third of each surface
// triangle around it), for pressure_scale_cap.
double surfaces_pressure_cap(const std::vector<vtkPolyData*>& surfaces) {
  std::vector<std::pair<double, double>> pressed;
  for (vtkPolyData* s : surfaces) {
    vtkDataArray* p = s->GetPointData()->GetArray(cp::contact_pressure.name);
    if (!p) continue;
    std::vector<double> area(static_cast<std::size_t>(s->GetNumberOfPoints()), 0.0);
    vtkIdType n = 0;
    const vtkIdType* ids = nullptr;
    vtkCellArray* polys = s->GetPolys();
    for (polys->InitTraversal(); polys->GetNextCell(n, ids);) {
      if (n != 3) continue;
      Vec3 a, b, c;
      s->GetPoint(ids[0], a.data()), s->GetPoint(ids[1], b.data()), s->GetPoint(ids[2], c.data());
      const double third = norm(cross(b - a, c - a)) / 6;
      for (int k = 0; k < 3; ++k) area[static_cast<std::size_t>(ids[k])] += third;
    }
    for (vtkIdType i = 0; i < s->GetNumberOfPoints(); ++i)
      if (const double q = p->GetComponent(i, 0); q > 0) pressed.emplace_back(q, area[static_cast<std::size_t>(i)]);
  }
  return pressure_scale_cap(pressed);
}

std::size_t nearest_frame(const Results& r, double t) {
  std::size_t best = 0;
  for (std::size_t k = 1; k < r.frames.size(); ++k)
    if (std::abs(r.frames[k].time - t) < std::abs(r.frames[best].time - t)) best = k;
  return best;
}

int body_index(const Results& r, const std::string& name) {
  for (std::size_t b = 0; b < r.bodies.size(); ++b)
    if (r.bodies[b] == name) return static_cast<int>(b);
  std::string names;
  for (const auto& b : r.bodies) names += (names.empty() ? "" : ", ") + b;
  throw InputError("command line", "--pressure-body", "a body of the run (" + names + ")", "\"" + name + "\"");
}

// The body the pressure is mapped on: --pressure-body, else the one carrying the peak pressure at
// the outputs (the contact pairs' slave side); -1 without contact.
int pressure_body(const Results& r, const Summary& s, const RenderOptions& opt) {
  if (!opt.pressure_body.empty()) return body_index(r, opt.pressure_body);
  return s.peak_pressure_outputs.body.empty() ? -1 : body_index(r, s.peak_pressure_outputs.body);
}

// A series with its own times (the windowed figures at the outputs, from run.json), drawn with
// its points marked beside a plot's history columns.
struct OutputSeries {
  std::string label;
  std::vector<double> time, value;  // s, plotted unit
};

void plot(const History& h, const fs::path& file, const std::string& title, const std::string& ylabel,
          const std::vector<std::pair<std::string, double>>& series, int w, int hgt, const std::vector<OutputSeries>& at_outputs = {},
          const std::map<std::string, std::string>& labels = {}) {
  if (!h.has(hc::time.name)) return;
  vtkNew<vtkTable> table;
  vtkNew<vtkDoubleArray> t;
  t->SetName("time (ms)");
  table->AddColumn(t);
  std::vector<std::string> present;
  for (const auto& [name, scale] : series)
    if (h.has(name)) {
      vtkNew<vtkDoubleArray> a;
      a->SetName(labels.count(name) ? labels.at(name).c_str() : name.c_str());  // the legend's text
      table->AddColumn(a);
      present.push_back(name);
    }
  if (present.empty()) return;
  const auto& time = h.column(hc::time.name);
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
  chart->SetShowLegend(present.size() + at_outputs.size() > 1);
  const unsigned char colors[5][3] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {148, 103, 189}, {255, 127, 14}};
  for (std::size_t k = 0; k < present.size(); ++k) {
    vtkPlot* line = chart->AddPlot(vtkChart::LINE);
    line->SetInputData(table, 0, static_cast<vtkIdType>(k + 1));
    line->SetColor(colors[k % 5][0], colors[k % 5][1], colors[k % 5][2], 255);
    line->SetWidth(2.0);
  }
  std::vector<vtkSmartPointer<vtkTable>> output_tables;  // alive until the picture is drawn
  for (std::size_t k = 0; k < at_outputs.size(); ++k) {
    const OutputSeries& o = at_outputs[k];
    if (o.time.empty()) continue;
    auto series_table = vtkSmartPointer<vtkTable>::New();
    vtkNew<vtkDoubleArray> x, y;
    x->SetName("time (ms)");
    y->SetName(o.label.c_str());
    series_table->AddColumn(x);
    series_table->AddColumn(y);
    series_table->SetNumberOfRows(static_cast<vtkIdType>(o.time.size()));
    for (std::size_t i = 0; i < o.time.size(); ++i)
      series_table->SetValue(static_cast<vtkIdType>(i), 0, o.time[i] * 1e3), series_table->SetValue(static_cast<vtkIdType>(i), 1, o.value[i]);
    output_tables.push_back(series_table);
    vtkPlot* line = chart->AddPlot(vtkChart::LINE);
    line->SetInputData(series_table, 0, 1);
    const auto& c = colors[(present.size() + k) % 5];
    line->SetColor(c[0], c[1], c[2], 255);
    line->SetWidth(2.5);
    if (auto* points = vtkPlotPoints::SafeDownCast(line)) points->SetMarkerStyle(vtkPlotPoints::CIRCLE), points->SetMarkerSize(8);
  }
  write_png(window, file);
}

}  // namespace

namespace {

struct Views {
  Vec3 view, up;    // the stress pictures
  double span = 1;  // the model's largest extent
  double bounds[6]{};
};

Views choose_views(vtkUnstructuredGrid* g, const RenderOptions& opt) {
  Views v;
  g->GetBounds(v.bounds);
  v.span = std::max({v.bounds[1] - v.bounds[0], v.bounds[3] - v.bounds[2], v.bounds[5] - v.bounds[4]});
  const auto axes = principal_axes(g->GetPoints());
  v.view = opt.view ? *opt.view : -1.0 * axes[0];  // along the least extent: the largest projected area
  v.up = axes[2];                                  // the longest axis up
  return v;
}

// The nodal von Mises (nodal_von_mises, as the interactive report's) as point field
// "von_mises_nodal": a smooth picture beside the per-tet one, whose jumps show the mesh.
void add_nodal_von_mises(vtkUnstructuredGrid* g) {
  const std::vector<double> values = nodal_von_mises(g);
  if (values.empty()) return;
  vtkNew<vtkDoubleArray> nodal;
  nodal->SetName("von_mises_nodal");
  nodal->SetNumberOfTuples(static_cast<vtkIdType>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) nodal->SetValue(static_cast<vtkIdType>(i), values[i]);
  g->GetPointData()->AddArray(nodal);
}

// The von Mises colour bar in MPa: the same colours as `vm_lut` (Pa), labelled in MPa.
vtkSmartPointer<vtkLookupTable> mpa_bar(vtkLookupTable* vm_lut) {
  const double* range = vm_lut->GetRange();
  return rainbow(1e-6 * range[0], 1e-6 * range[1], true);
}

std::string von_mises_picture(const Results& r, std::size_t k, const Views& v, vtkLookupTable* vm_lut, const fs::path& report,
                              const RenderOptions& opt, bool nodal = false) {
  const auto g = load_state(r.frames[k].file);
  if (nodal) add_nodal_von_mises(g);
  auto window = offscreen(opt.width, opt.height);
  auto ren = white_renderer();
  window->AddRenderer(ren);
  ren->AddActor(nodal ? colored(surface(g), "von_mises_nodal", false, vm_lut) : colored(surface(g), cc::von_mises.name, true, vm_lut));
  add_scalar_bar(ren, mpa_bar(vm_lut), "von Mises (MPa)");
  add_text(ren,
           "t = " + ms(r.frames[k].time) + " ms   von Mises stress (MPa) on the deformed bodies, " +
               (nodal ? "nodal average (volume-weighted over each node's tets)" : "per tet") + ", log scale",
           20, opt.height - 40);
  look(ren, v.bounds, 2 * v.span * v.view, v.up, 1.3);
  add_view_keys(window, ren);
  const std::string name = (nodal ? "von_mises_nodal_t" : "von_mises_t") + ms(r.frames[k].time) + "ms.png";
  write_png(window, report / name);
  return name;
}

// A section through the peak pressure (or the middle), normal to the longest axis of the body
// with the pressure (or of the model): materials and von Mises side by side.
bool section_picture(const Results& r, const Summary& s, const Views& v, vtkLookupTable* vm_lut, const fs::path& report, const RenderOptions& opt) {
  const std::size_t k = s.contact_occurred ? nearest_frame(r, s.peak_pressure_outputs.time) : r.frames.size() - 1;
  const auto g = load_state(r.frames[k].file);
  const int pb = pressure_body(r, s, opt);
  const auto axes = principal_axes(pb >= 0 ? body_cells(g, pb)->GetPoints() : g->GetPoints());
  const Vec3 normal = opt.section_normal ? (1.0 / norm(*opt.section_normal)) * *opt.section_normal : axes[2];
  double b[6];
  g->GetBounds(b);
  Vec3 origin{0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0.5 * (b[4] + b[5])};
  if (s.contact_occurred && s.peak_pressure_outputs.index > 0) origin = s.peak_pressure_outputs.position;
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(origin.data());
  plane->SetNormal(normal.data());
  vtkNew<vtkCutter> cut;
  cut->SetInputData(g);
  cut->SetCutFunction(plane);
  cut->Update();
  vtkPolyData* section = cut->GetOutput();
  if (section->GetNumberOfCells() == 0) return false;
  auto window = offscreen(opt.width * 2, opt.height);
  // Materials are categories: one colour and one named swatch each (an indexed lookup table's
  // annotations), not a continuous bar whose in-between values mean nothing.
  auto mat_lut = vtkSmartPointer<vtkLookupTable>::New();
  mat_lut->IndexedLookupOn();
  mat_lut->SetNumberOfTableValues(static_cast<vtkIdType>(std::max<std::size_t>(1, r.materials.size())));
  for (std::size_t m = 0; m < r.materials.size(); ++m) {
    const double hue = 0.1 + 0.65 * static_cast<double>(m) / std::max<double>(1, static_cast<double>(r.materials.size()) - 1);
    double rgb[3];
    vtkMath::HSVToRGB(hue, 0.75, 0.9, rgb, rgb + 1, rgb + 2);
    mat_lut->SetTableValue(static_cast<vtkIdType>(m), rgb[0], rgb[1], rgb[2], 1.0);
    mat_lut->SetAnnotation(vtkVariant(static_cast<int>(m)), r.materials[m]);
  }
  double sb[6];
  section->GetBounds(sb);
  std::ostringstream caption;
  caption << std::setprecision(3) << "section through (" << ms(origin[0]) << ", " << ms(origin[1]) << ", " << ms(origin[2]) << ") mm, normal ("
          << normal[0] << ", " << normal[1] << ", " << normal[2] << "), t = " << ms(r.frames[k].time) << " ms";
  for (int side = 0; side < 2; ++side) {
    auto ren = white_renderer();
    ren->SetViewport(0.5 * side, 0, 0.5 * side + 0.5, 1);
    window->AddRenderer(ren);
    if (side == 0) {
      ren->AddActor(colored(section, cc::material.name, true, mat_lut));
      add_scalar_bar(ren, mat_lut, "material");
    } else {
      ren->AddActor(colored(section, cc::von_mises.name, true, vm_lut));
      add_scalar_bar(ren, mpa_bar(vm_lut), "von Mises (MPa)");
    }
    add_text(ren, caption.str(), 20, opt.height - 40, 18);
    look(ren, sb, 2 * v.span * normal, axes[1], 1.2);
    add_view_keys(window, ren);
  }
  write_png(window, report / "section.png");
  return true;
}

// The contact pressure of state k on body pb (`body`: its surface in that state), seen along `view`
// (from the contact partner's side), coloured from 0 to scale_max (unpressed surface grey), its
// largest value on the body marked. Returns false when the body carries no pressure in that state
// (no picture written).
bool pressure_picture(const Results& r, std::size_t k, int pb, vtkPolyData* body, const Vec3& view, double scale_max, const Views& v,
                      const fs::path& file, const RenderOptions& opt) {
  vtkDataArray* p = body->GetPointData()->GetArray(cp::contact_pressure.name);
  if (!p) return false;
  vtkIdType peak = -1;
  for (vtkIdType i = 0; i < body->GetNumberOfPoints(); ++i)
    if (p->GetComponent(i, 0) > 0 && (peak < 0 || p->GetComponent(i, 0) > p->GetComponent(peak, 0))) peak = i;
  if (peak < 0) return false;
  Vec3 at;
  body->GetPoint(peak, at.data());
  double hb[6];
  body->GetBounds(hb);
  auto window = offscreen(opt.width, opt.height);
  auto ren = white_renderer();
  window->AddRenderer(ren);
  add_pressure_map(ren, body, scale_max, at, 0.012 * v.span);
  std::ostringstream caption;
  const std::string name = static_cast<std::size_t>(pb) < r.bodies.size() ? r.bodies[static_cast<std::size_t>(pb)] : "body";
  caption << std::setprecision(3) << "t = " << ms(r.frames[k].time) << " ms   contact pressure on " << name << "; peak "
          << p->GetComponent(peak, 0) / 1e6 << " MPa (black dot) at (" << ms(at[0]) << ", " << ms(at[1]) << ", " << ms(at[2]) << ") mm";
  add_text(ren, caption.str(), 20, opt.height - 40, 18);
  std::ostringstream scale;
  scale << std::setprecision(3) << "colour scale 0 - " << scale_max / 1e6
        << " MPa: 99.5 % of the pressed area of all outputs lies below it (red: at or above)";
  add_text(ren, scale.str(), 20, 24, 16);  // at the foot, clear of the model
  const auto axes = principal_axes(body->GetPoints());
  look(ren, hb, 2 * v.span * view, axes[2], 1.2);
  add_view_keys(window, ren);
  write_png(window, file);
  return true;
}

// pressure.png: the state with the peak pressure at the outputs, seen from its own pressed side.
// pressure_t<ms>ms.png: every chosen state with contact on that body, on one colour scale (0 to the
// area-weighted 99.5th percentile over the outputs, pressure_scale_cap) and one view (the pressed side of the state with the most nodes in contact),
// so the pictures side by side show how the pressure map changes in time.
std::vector<std::string> pressure_pictures(const Results& r, const Summary& s, const std::vector<std::size_t>& chosen, const Views& v,
                                           const fs::path& report, const RenderOptions& opt) {
  std::vector<std::string> written;
  const int pb = std::max(0, pressure_body(r, s, opt));
  std::map<std::size_t, vtkSmartPointer<vtkPolyData>> bodies;  // each state read once
  const auto body_at = [&](std::size_t k) -> vtkPolyData* {
    auto& b = bodies[k];
    if (!b) b = surface(body_cells(load_state(r.frames[k].file), pb));
    return b;
  };
  std::vector<vtkPolyData*> every_output;
  for (std::size_t k = 0; k < r.frames.size(); ++k)
    if (s.frames[k].contact_nodes > 0) every_output.push_back(body_at(k));
  const double cap = surfaces_pressure_cap(every_output), peak = s.peak_pressure_outputs.value;
  const double scale = cap > 0 && cap < peak ? cap : peak;
  const std::size_t peak_k = nearest_frame(r, s.peak_pressure_outputs.time);
  if (pressure_picture(r, peak_k, pb, body_at(peak_k), pressed_side(body_at(peak_k)), scale, v, report / "pressure.png", opt))
    written.push_back("pressure.png");
  std::size_t widest = chosen.front();
  for (std::size_t k : chosen)
    if (s.frames[k].contact_nodes > s.frames[widest].contact_nodes) widest = k;
  const Vec3 view = pressed_side(body_at(widest));
  for (std::size_t k : chosen) {
    if (s.frames[k].contact_nodes == 0) continue;
    const std::string name = "pressure_t" + ms(r.frames[k].time) + "ms.png";
    if (pressure_picture(r, k, pb, body_at(k), view, scale, v, report / name, opt)) written.push_back(name);
  }
  return written;
}

// The unrolled grip map (grip_map_picture): the flat pressure map in mm with its axes, the peak dot
// and the caption.
void draw_unrolled_map(vtkPolyData* map, double peak, const Vec3& peak_point, double radius, const std::string& caption, const fs::path& file,
                       const RenderOptions& opt) {
  auto window = offscreen(opt.width, opt.height);
  auto ren = white_renderer();
  window->AddRenderer(ren);
  const double cap = surfaces_pressure_cap({map});  // as the pressure pictures' (pressure_scale_cap)
  const double scale = cap > 0 && cap < peak ? cap : peak;
  add_pressure_map(ren, map, scale, peak_point, 1.5);
  std::ostringstream foot;
  foot << std::setprecision(3) << "colour scale 0 - " << scale / 1e6 << " MPa: 99.5 % of the pressed area lies below it (red: at or above)";
  add_text(ren, foot.str(), 20, opt.height - 66, 16);  // under the caption (the foot holds the axis title)
  double b[6];
  map->GetBounds(b);
  b[0] = 0, b[1] = 1e3 * radius * 2 * M_PI, b[4] = -1, b[5] = 1;
  vtkCamera* cam = ren->GetActiveCamera();
  cam->ParallelProjectionOn();
  cam->SetFocalPoint(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 0);
  cam->SetPosition(0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), 100);
  cam->SetViewUp(0, 1, 0);
  ren->ResetCamera(b);
  cam->SetParallelScale(0.62 * std::max(b[3] - b[2], (b[1] - b[0]) * opt.height / opt.width));
  vtkNew<vtkCubeAxesActor> ticks;
  ticks->SetBounds(b);
  ticks->SetCamera(cam);
  ticks->SetXTitle("around the handle (mm of its surface)");
  ticks->SetYTitle("along (mm)");
  ticks->ZAxisVisibilityOff();
  ticks->SetFlyModeToOuterEdges();
  for (int a = 0; a < 3; ++a) ticks->GetTitleTextProperty(a)->SetColor(0, 0, 0), ticks->GetLabelTextProperty(a)->SetColor(0, 0, 0);
  ticks->GetXAxesLinesProperty()->SetColor(0, 0, 0);
  ticks->GetYAxesLinesProperty()->SetColor(0, 0, 0);
  ren->AddActor(ticks);
  add_text(ren, caption, 20, opt.height - 40, 18);
  write_png(window, file);
}

// grip_map.png: the handle's pressure on the hand at the last output, unrolled around the handle
// as grip studies show it: arc length at the handle's surface around its axis against length
// along it. The handle's axis is its longest principal axis through its centroid, its radius the
// largest distance of its surface from that axis; the skin within 4 mm of its side is drawn (the
// folds' self-contact further out is not the handle's, and a pad pressing an end cap is left out). The cut is placed where the least
// pressure is, so the pressed band is whole.
bool grip_map_picture(const Results& r, const Summary& s, const fs::path& file, const RenderOptions& opt) {
  if (!s.grasp.on || r.frames.empty()) return false;
  auto point = [](vtkPolyData* poly, vtkIdType i) {
    Vec3 x;
    poly->GetPoint(i, x.data());
    return x;
  };
  int handle = -1, hand = -1;
  for (std::size_t b = 0; b < r.bodies.size(); ++b)
    if (r.bodies[b] == s.grasp.handle) handle = static_cast<int>(b);
  if (handle < 0) return false;
  hand = opt.pressure_body.empty() ? (handle == 0 ? 1 : 0) : body_index(r, opt.pressure_body);
  const std::size_t k = r.frames.size() - 1;
  auto grid = load_state(r.frames[k].file);
  auto handle_surface = surface(body_cells(grid, handle));
  auto skin = surface(body_cells(grid, hand));
  vtkDataArray* p = skin->GetPointData()->GetArray(cp::contact_pressure.name);
  if (!p || handle_surface->GetNumberOfPoints() == 0) return false;
  const Vec3 axis = principal_axes(handle_surface->GetPoints())[2];
  Vec3 c{0, 0, 0};
  for (vtkIdType i = 0; i < handle_surface->GetNumberOfPoints(); ++i) c = c + point(handle_surface, i);
  c = (1.0 / static_cast<double>(handle_surface->GetNumberOfPoints())) * c;
  auto radial = [&](const Vec3& x) {
    const Vec3 d = x - c;
    return d - dot(d, axis) * axis;
  };
  double radius = 0, a_lo = 1e300, a_hi = -1e300;
  for (vtkIdType i = 0; i < handle_surface->GetNumberOfPoints(); ++i) {
    const Vec3 x = point(handle_surface, i);
    radius = std::max(radius, norm(radial(x)));
    a_lo = std::min(a_lo, dot(x - c, axis)), a_hi = std::max(a_hi, dot(x - c, axis));
  }
  // Angle 0 towards the hand's centroid; e2 completes a right-handed frame with the axis.
  Vec3 hc{0, 0, 0};
  for (vtkIdType i = 0; i < skin->GetNumberOfPoints(); ++i) hc = hc + point(skin, i);
  Vec3 e1 = radial((1.0 / std::max<double>(1, static_cast<double>(skin->GetNumberOfPoints()))) * hc);
  if (norm(e1) < 1e-12) e1 = std::abs(axis[0]) < 0.9 ? radial(c + Vec3{1, 0, 0}) : radial(c + Vec3{0, 1, 0});
  e1 = (1.0 / norm(e1)) * e1;
  const Vec3 e2 = cross(axis, e1);
  const vtkIdType n = skin->GetNumberOfPoints();
  std::vector<double> angle(static_cast<std::size_t>(n)), along(static_cast<std::size_t>(n));
  std::vector<char> near(static_cast<std::size_t>(n), 0);
  std::array<double, 36> load_in{};
  double peak = 0;
  vtkIdType peak_at = -1;
  for (vtkIdType i = 0; i < n; ++i) {
    const Vec3 x = point(skin, i), d = radial(x);
    const auto u = static_cast<std::size_t>(i);
    angle[u] = std::atan2(dot(d, e2), dot(d, e1)) + M_PI;  // [0, 2 pi)
    along[u] = dot(x - c, axis);
    near[u] = std::abs(norm(d) - radius) < 0.004 && along[u] > a_lo - 0.002 && along[u] < a_hi + 0.002;  // the side, not the ends
    const double q = p->GetComponent(i, 0);
    if (!near[u] || !(q > 0)) continue;
    load_in[std::min<std::size_t>(35, static_cast<std::size_t>(angle[u] / (2 * M_PI) * 36))] += q;
    if (q > peak) peak = q, peak_at = i;
  }
  if (peak_at < 0) return false;
  const auto empty_bin = static_cast<std::size_t>(std::min_element(load_in.begin(), load_in.end()) - load_in.begin());
  const double cut = (static_cast<double>(empty_bin) + 0.5) / 36 * 2 * M_PI;
  // The flat map, in mm: x = R (angle from the cut), y = along the axis.
  vtkNew<vtkPoints> flat;
  vtkNew<vtkDoubleArray> pressure;
  pressure->SetName(cp::contact_pressure.name);
  for (vtkIdType i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    double a = angle[u] - cut;
    if (a < 0) a += 2 * M_PI;
    angle[u] = a;
    flat->InsertNextPoint(1e3 * radius * a, 1e3 * along[u], 0);
    pressure->InsertNextValue(near[u] ? p->GetComponent(i, 0) : 0.0);
  }
  vtkNew<vtkCellArray> triangles;
  vtkIdList* ids = vtkIdList::New();
  for (vtkIdType t = 0; t < skin->GetNumberOfCells(); ++t) {
    skin->GetCellPoints(t, ids);
    if (ids->GetNumberOfIds() != 3) continue;
    bool keep = true;
    double lo = 1e9, hi = -1e9;
    for (vtkIdType v = 0; v < 3; ++v) {
      const auto u = static_cast<std::size_t>(ids->GetId(v));
      keep = keep && near[u];
      lo = std::min(lo, angle[u]), hi = std::max(hi, angle[u]);
    }
    if (keep && hi - lo < M_PI) triangles->InsertNextCell(ids);  // a triangle across the cut is left out
  }
  ids->Delete();
  vtkNew<vtkPolyData> map;
  map->SetPoints(flat);
  map->SetPolys(triangles);
  map->GetPointData()->AddArray(pressure);
  Vec3 peak_point;
  flat->GetPoint(peak_at, peak_point.data());
  std::ostringstream caption;
  caption << std::setprecision(3) << "t = " << ms(r.frames[k].time) << " ms   " << r.bodies[static_cast<std::size_t>(hand)] << " on '"
          << s.grasp.handle << "' (radius " << 1e3 * radius << " mm), unrolled; peak " << peak / 1e6 << " MPa (black dot); grip "
          << s.grasp.final_grip << " N";
  draw_unrolled_map(map, peak, peak_point, radius, caption.str(), file, opt);
  return true;
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
    // The views of the first state frame them all (bodies move little over a run).
    const Views views = choose_views(load_state(r.frames[chosen.front()].file), opt);
    for (std::size_t k : chosen) written.push_back(von_mises_picture(r, k, views, vm_lut, report, opt));
    // The nodal average beside the per-tet picture, at the chosen output with the highest stress.
    double peak_time = r.frames[chosen.back()].time;
    for (const auto& m : s.von_mises)
      if (m.von_mises.value >= vm_max) peak_time = m.von_mises.time;
    std::size_t highest = chosen.front();
    for (std::size_t k : chosen)
      if (std::abs(r.frames[k].time - peak_time) < std::abs(r.frames[highest].time - peak_time)) highest = k;
    written.push_back(von_mises_picture(r, highest, views, vm_lut, report, opt, true));
    if (section_picture(r, s, views, vm_lut, report, opt)) written.push_back("section.png");
    if (s.contact_occurred && s.peak_pressure_outputs.value > 0)
      for (std::string& name : pressure_pictures(r, s, chosen, views, report, opt)) written.push_back(std::move(name));
    if (grip_map_picture(r, s, report / "grip_map.png", opt)) written.push_back("grip_map.png");
  }
  const History& h = r.history;
  const int pw = 900, ph = 600;
  // Force and area: the windowed figures at the outputs (run.json contact.at_outputs, what
  // summary.md and the interactive page report) over the single steps' history, which carries the
  // first-touch impulses; the peak pressure windowed over the one-step impulse / dt.
  OutputSeries force{"windowed, at the outputs", {}, {}}, area{"windowed, at the outputs", {}, {}};
  if (const auto run = nlohmann::json::parse(r.run_json, nullptr, false); run.is_object() && run.contains("contact"))
    for (const auto& o : run["contact"].value("at_outputs", nlohmann::json::array()))
      if (o.contains("windowed_normal_force") && o.contains("windowed_area")) {
        force.time.push_back(o["time"].get<double>()), force.value.push_back(o["windowed_normal_force"].get<double>());
        area.time.push_back(o["time"].get<double>()), area.value.push_back(1e6 * o["windowed_area"].get<double>());
      }
  const std::map<std::string, std::string> legend{{hc::contact_force.name, "one step (carries the impulses)"},
                                                  {hc::contact_area.name, "one step"},
                                                  {hc::peak_pressure.name, "windowed (contact_solver.pressure_window)"},
                                                  {hc::peak_step_pressure.name, "one step (impulse / dt)"}};
  plot(h, report / "plot_contact_force.png", "total contact force", "N", {{hc::contact_force.name, 1.0}}, pw, ph, {force}, legend);
  plot(h, report / "plot_contact_area.png", "contact area", "mm^2", {{hc::contact_area.name, 1e6}}, pw, ph, {area}, legend);
  plot(h, report / "plot_peak_pressure.png", "peak contact pressure", "MPa", {{hc::peak_step_pressure.name, 1e-6}, {hc::peak_pressure.name, 1e-6}},
       pw, ph, {}, legend);
  plot(h, report / "plot_energies.png", "energies", "J",
       {{hc::kinetic_energy.name, 1.0},
        {hc::internal_energy.name, 1.0},
        {hc::contact_work_normal.name, 1.0},
        {hc::contact_work_friction.name, 1.0},
        {hc::energy_balance_error.name, 1.0}},
       pw, ph);
  // |R| of every support, from its reaction_<name>_x, _y, _z columns.
  History reactions;
  std::vector<std::pair<std::string, double>> series;
  const std::string prefix = contracts::history::reaction.prefix;
  for (const std::string& name : h.names)
    if (name.rfind(prefix, 0) == 0 && name.size() > prefix.size() + 2 && name.compare(name.size() - 2, 2, "_x") == 0) {
      const std::string base = name.substr(0, name.size() - 2), label = "|R| " + base.substr(prefix.size());
      if (!h.has(base + "_y") || !h.has(base + "_z")) continue;
      const auto &x = h.column(base + "_x"), &y = h.column(base + "_y"), &z = h.column(base + "_z");
      std::vector<double> mag(x.size());
      for (std::size_t i = 0; i < x.size(); ++i) mag[i] = std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]);
      reactions.columns[label] = std::move(mag);
      reactions.names.push_back(label);
      series.push_back({label, 1.0});
    }
  if (!series.empty()) {
    reactions.columns[hc::time.name] = h.column(hc::time.name);
    reactions.names.insert(reactions.names.begin(), hc::time.name);
    plot(reactions, report / "plot_reactions.png", "support reactions", "N", series, pw, ph);
  }
  if (s.grasp.on) {
    std::vector<std::pair<std::string, double>> grip{{hc::grip_force.name, 1.0}, {hc::grip_target.name, 1.0}};
    for (const auto& d : s.grasp.digits) grip.push_back({std::string(hc::digit_force.prefix) + d.name, 1.0});
    plot(h, report / "plot_grip.png", "grip force and each digit's share", "N", grip, pw, ph);
    written.push_back("plot_grip.png");
  }
  for (const char* f : {"plot_contact_force.png", "plot_contact_area.png", "plot_peak_pressure.png", "plot_energies.png", "plot_reactions.png"})
    if (fs::exists(report / f)) written.push_back(f);
  return written;
}

double pressure_scale_cap(std::vector<std::pair<double, double>> pressed) {
  double total = 0;
  for (const auto& [q, a] : pressed) total += a;
  if (pressed.empty()) return 0;
  std::sort(pressed.begin(), pressed.end());
  double below = 0;
  for (const auto& [q, a] : pressed)
    if ((below += a) >= 0.995 * total) return q;
  return pressed.back().first;
}

}  // namespace tactus::postproc
