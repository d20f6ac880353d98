// The interactive report (web_report.hpp): the bodies' boundary surface and its fields at every
// output state, written as JavaScript data files beside a vendored three.js page.
#include "tactus/postproc/web_report.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_map>

#include "state_files.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/embedded.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/vec3.hpp"
#include "tactus/postproc/render.hpp"

namespace tactus {
std::vector<EmbeddedFile> web_report_assets();  // index.html, tactus-report.js, three-report.min.js (postproc/CMakeLists.txt)
}

namespace fs = std::filesystem;

namespace tactus::postproc {

namespace cc = contracts::cell;
namespace cp = contracts::point;
namespace hc = contracts::history;

void PercentileCap::add(double value, double weight) {
  if (!(value > 0) || !(weight > 0)) return;
  peak_ = std::max(peak_, value);
  const double bin = std::floor((std::log10(value) - kLowestDecade) * kBinsPerDecade);
  const auto last = static_cast<double>(weight_.size() - 1);
  weight_[static_cast<std::size_t>(std::clamp(bin, 0.0, last))] += weight;
  total_ += weight;
}

double PercentileCap::cap() const {
  double below = 0;
  for (std::size_t b = 0; b < weight_.size(); ++b)
    if ((below += weight_[b]) >= 0.995 * total_ && total_ > 0)
      return std::min(peak_, std::pow(10.0, kLowestDecade + static_cast<double>(b + 1) / kBinsPerDecade));
  return peak_;
}

namespace {

std::string base64(const void* data, std::size_t bytes) {
  static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((bytes + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes; i += 3) {
    const unsigned v = (unsigned{p[i]} << 16) | (i + 1 < bytes ? unsigned{p[i + 1]} << 8 : 0u) | (i + 2 < bytes ? unsigned{p[i + 2]} : 0u);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += i + 1 < bytes ? kDigits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes ? kDigits[v & 63] : '=';
  }
  return out;
}

template <class T>
std::string base64(const std::vector<T>& v) {
  return base64(v.data(), v.size() * sizeof(T));
}

// The bodies' boundary: the tet faces that belong to one tet only, oriented outward in the
// reference configuration. Surface vertices are numbered compactly (node: their .vtu point).
struct Surface {
  std::vector<std::uint32_t> node;                  // surface vertex -> .vtu point
  std::vector<std::array<std::uint32_t, 3>> faces;  // surface vertices
  std::vector<std::uint32_t> face_tet;              // .vtu cell of each face
  std::vector<std::array<vtkIdType, 4>> tets;       // every cell's points
};

Surface boundary_surface(vtkUnstructuredGrid* g, const std::vector<Vec3>& X, const std::string& file) {
  Surface s;
  const vtkIdType cells = g->GetNumberOfCells();
  s.tets.resize(static_cast<std::size_t>(cells));
  struct Face {
    std::array<vtkIdType, 3> key, points;
    vtkIdType cell;
  };
  std::vector<Face> faces;
  faces.reserve(4 * static_cast<std::size_t>(cells));
  static constexpr int kFaceOf[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  for (vtkIdType c = 0; c < cells; ++c) {
    vtkIdType n = 0;
    const vtkIdType* p = nullptr;
    g->GetCellPoints(c, n, p);
    if (n != 4) throw InputError(file, "cell " + std::to_string(c + 1), "linear tetrahedra (4 points)", std::to_string(n) + " points");
    auto& t = s.tets[static_cast<std::size_t>(c)];
    std::copy(p, p + 4, t.begin());
    for (int f = 0; f < 4; ++f) {
      Face face{{t[kFaceOf[f][0]], t[kFaceOf[f][1]], t[kFaceOf[f][2]]}, {}, c};
      face.points = face.key;
      // Outward: the fourth point lies behind the face.
      const Vec3 &a = X[static_cast<std::size_t>(face.points[0])], &b = X[static_cast<std::size_t>(face.points[1])],
                 &d = X[static_cast<std::size_t>(t[f])];
      if (dot(cross(b - a, X[static_cast<std::size_t>(face.points[2])] - a), d - a) > 0) std::swap(face.points[1], face.points[2]);
      std::sort(face.key.begin(), face.key.end());
      faces.push_back(face);
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.key < b.key; });
  std::vector<std::int64_t> vertex_of(X.size(), -1);  // .vtu point -> surface vertex, -1 inside
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j == i + 1) {
      std::array<std::uint32_t, 3> tri{};
      for (int k = 0; k < 3; ++k) {
        auto& v = vertex_of[static_cast<std::size_t>(faces[i].points[k])];
        if (v < 0) v = static_cast<std::int64_t>(s.node.size()), s.node.push_back(static_cast<std::uint32_t>(faces[i].points[k]));
        tri[k] = static_cast<std::uint32_t>(v);
      }
      s.faces.push_back(tri);
      s.face_tet.push_back(static_cast<std::uint32_t>(faces[i].cell));
    }
    i = j;
  }
  return s;
}

// One state's arrays on the surface vertices and faces (float, as the page draws them).
struct StateFields {
  std::vector<float> displacement, pressure, von_mises_nodal, von_mises_face;
  bool has_pressure = false;
  // For the pressure tables (double): current position, friction traction, tributary area.
  std::vector<Vec3> position, traction;
  std::vector<double> area, pressure_pa;
};

// A grasp state's region name per surface vertex (point field grip_region, names in field data
// grip_region_names); empty names elsewhere, and all empty for a state without them.
std::vector<std::string> vertex_regions(vtkUnstructuredGrid* g, const Surface& s) {
  std::vector<std::string> out(s.node.size());
  vtkDataArray* region = g->GetPointData()->GetArray(cp::grip_region.name);
  auto* names = vtkStringArray::SafeDownCast(g->GetFieldData()->GetAbstractArray(contracts::kGripRegionNames));
  if (!region || !names) return out;
  for (std::size_t v = 0; v < s.node.size(); ++v) {
    const double r = region->GetComponent(static_cast<vtkIdType>(s.node[v]), 0);
    if (r >= 0 && r < static_cast<double>(names->GetNumberOfValues())) out[v] = names->GetValue(static_cast<vtkIdType>(r));
  }
  return out;
}

struct Peak {
  double value = 0;
  std::size_t state = 0;
  long id = -1;  // 1-based node or tet
  Vec3 position{0, 0, 0};
  nlohmann::json json(const std::vector<Frame>& frames) const {
    return {{"value", value}, {"state", state}, {"time", frames.empty() ? 0.0 : frames[state].time}, {"id", id}, {"position", position}};
  }
};

struct Scan {
  std::vector<Vec3> X;  // reference positions of the .vtu points
  Surface surface;
  std::vector<std::uint32_t> tet_body;     // each cell's body index (the "body" field; 0 without it)
  std::vector<std::string> vertex_region;  // a grasp's hand region per surface vertex (constant over the run), else ""
  std::vector<std::size_t> states;         // frames shown
  std::vector<char> ever_pressed;          // per surface vertex
  std::vector<std::pair<double, double>> pressed;
  PercentileCap stress;
  double displacement_max = 0;
  Peak pressure_peak, stress_peak, displacement_peak;
  std::vector<std::string> missing;
};

double tet_volume(const std::array<vtkIdType, 4>& t, const std::vector<Vec3>& x) {
  const Vec3& a = x[static_cast<std::size_t>(t[0])];
  return std::abs(dot(cross(x[static_cast<std::size_t>(t[1])] - a, x[static_cast<std::size_t>(t[2])] - a), x[static_cast<std::size_t>(t[3])] - a)) /
         6;
}

// A state's fields on the surface; with `scan`, also its contribution to the colour scales and peaks.
StateFields state_fields(vtkUnstructuredGrid* g, std::size_t k, const Surface& s, Scan* scan, const std::string& file) {
  const std::size_t N = static_cast<std::size_t>(g->GetNumberOfPoints()), V = s.node.size();
  vtkDataArray* u = g->GetPointData()->GetArray(cp::displacement.name);
  vtkDataArray* p = g->GetPointData()->GetArray(cp::contact_pressure.name);
  vtkDataArray* vm = g->GetCellData()->GetArray(cc::von_mises.name);
  if (!vm) throw InputError(file, cc::von_mises.name, "a cell field von_mises (tactus-solve state)", "none");
  std::vector<Vec3> x(N);
  for (std::size_t i = 0; i < N; ++i) g->GetPoint(static_cast<vtkIdType>(i), x[i].data());
  StateFields f;
  f.displacement.resize(3 * V);
  f.has_pressure = p != nullptr;
  f.pressure.assign(V, 0.0f);
  f.position.resize(V);
  f.traction.assign(V, Vec3{0, 0, 0});
  vtkDataArray* traction = g->GetPointData()->GetArray(cp::contact_traction.name);
  for (std::size_t v = 0; v < V; ++v) {
    const auto i = static_cast<vtkIdType>(s.node[v]);
    Vec3 d{0, 0, 0};
    if (u) d = {u->GetComponent(i, 0), u->GetComponent(i, 1), u->GetComponent(i, 2)};
    for (int c = 0; c < 3; ++c) f.displacement[3 * v + static_cast<std::size_t>(c)] = static_cast<float>(d[static_cast<std::size_t>(c)]);
    if (scan && norm(d) > scan->displacement_peak.value) scan->displacement_peak = {norm(d), k, static_cast<long>(s.node[v]) + 1, x[s.node[v]]};
    if (p) f.pressure[v] = static_cast<float>(std::max(0.0, p->GetComponent(i, 0)));
    f.pressure_pa.push_back(p ? std::max(0.0, p->GetComponent(i, 0)) : 0.0);
    if (traction) f.traction[v] = {traction->GetComponent(i, 0), traction->GetComponent(i, 1), traction->GetComponent(i, 2)};
    f.position[v] = x[s.node[v]];
  }
  // Nodal pressure areas, weighing the pressed nodes in the scale's cap and the pressure tables.
  std::vector<double> area(V, 0.0);
  for (const auto& t : s.faces) {
    const Vec3 &a = x[s.node[t[0]]], &b = x[s.node[t[1]]], &c = x[s.node[t[2]]];
    for (std::uint32_t v : t) area[v] += norm(cross(b - a, c - a)) / 6;
  }
  // The solver's own tributary areas where it wrote them (pressure x area is then each node's
  // reaction); older results: a third of the current surface triangles around the node.
  if (vtkDataArray* a = g->GetPointData()->GetArray(cp::contact_area.name))
    for (std::size_t v = 0; v < V; ++v) area[v] = a->GetComponent(static_cast<vtkIdType>(s.node[v]), 0);
  f.area = area;
  for (std::size_t v = 0; v < V && scan; ++v)
    if (f.pressure[v] > 0) {
      scan->pressed.emplace_back(f.pressure[v], area[v]);
      scan->ever_pressed[v] = 1;
      if (f.pressure[v] > scan->pressure_peak.value) scan->pressure_peak = {f.pressure[v], k, static_cast<long>(s.node[v]) + 1, x[s.node[v]]};
    }
  // von Mises: per tet (its peak and the volume-weighted cap), and nodal at the surface vertices.
  for (std::size_t e = 0; e < s.tets.size() && scan; ++e) {
    const double value = vm->GetComponent(static_cast<vtkIdType>(e), 0), volume = tet_volume(s.tets[e], x);
    scan->stress.add(value, volume);
    if (value > scan->stress_peak.value) {
      Vec3 centre{0, 0, 0};
      for (vtkIdType q : s.tets[e]) centre = centre + 0.25 * x[static_cast<std::size_t>(q)];
      scan->stress_peak = {value, k, static_cast<long>(e) + 1, centre};
    }
  }
  const std::vector<double> nodal = nodal_von_mises(g);
  f.von_mises_nodal.resize(V);
  for (std::size_t v = 0; v < V; ++v) f.von_mises_nodal[v] = static_cast<float>(nodal[s.node[v]]);
  f.von_mises_face.resize(s.faces.size());
  for (std::size_t i = 0; i < s.faces.size(); ++i)
    f.von_mises_face[i] = static_cast<float>(vm->GetComponent(static_cast<vtkIdType>(s.face_tet[i]), 0));
  return f;
}

// The output states that can be read and match the first one's mesh; the others are named in
// scan.missing and left out of the page.
Scan scan_states(const Results& r) {
  Scan scan;
  scan.missing = r.missing;
  for (std::size_t k = 0; k < r.frames.size(); ++k) {
    const std::string file = r.frames[k].file.string();
    vtkSmartPointer<vtkUnstructuredGrid> g;
    try {
      g = load_state(r.frames[k].file);
    } catch (const Error& e) {
      scan.missing.push_back("state " + std::to_string(k) + " (t = " + std::to_string(r.frames[k].time) + " s): " + e.what());
      continue;
    }
    if (scan.states.empty()) {
      const std::size_t N = static_cast<std::size_t>(g->GetNumberOfPoints());
      vtkDataArray* u = g->GetPointData()->GetArray(cp::displacement.name);
      scan.X.resize(N);
      for (std::size_t i = 0; i < N; ++i) {
        g->GetPoint(static_cast<vtkIdType>(i), scan.X[i].data());
        if (u)
          for (int c = 0; c < 3; ++c) scan.X[i][static_cast<std::size_t>(c)] -= u->GetComponent(static_cast<vtkIdType>(i), c);
      }
      scan.surface = boundary_surface(g, scan.X, file);
      scan.tet_body.assign(scan.surface.tets.size(), 0);
      if (vtkDataArray* b = g->GetCellData()->GetArray(cc::body.name))
        for (std::size_t e = 0; e < scan.tet_body.size(); ++e)
          scan.tet_body[e] = static_cast<std::uint32_t>(b->GetComponent(static_cast<vtkIdType>(e), 0));
      scan.vertex_region = vertex_regions(g, scan.surface);
      scan.ever_pressed.assign(scan.surface.node.size(), 0);
    } else if (static_cast<std::size_t>(g->GetNumberOfPoints()) != scan.X.size() ||
               static_cast<std::size_t>(g->GetNumberOfCells()) != scan.surface.tets.size()) {
      scan.missing.push_back("state " + std::to_string(k) + ": " + file + " has another mesh than the first state");
      continue;
    }
    state_fields(g, k, scan.surface, &scan, file);
    scan.states.push_back(k);
  }
  return scan;
}

// Vertex clustering (Rossignac and Borrel) of the vertices that are never pressed: each grid cell
// of size h keeps one of its vertices, faces are re-pointed to those and the collapsed ones
// dropped. Pressed vertices keep their own place, so the contact patch is drawn in full. Returns
// the kept faces.
std::vector<std::size_t> cluster_faces(const Surface& s, const std::vector<Vec3>& X, const std::vector<char>& pressed, double h) {
  std::map<std::array<long, 3>, std::uint32_t> representative;
  std::vector<std::uint32_t> to(s.node.size());
  for (std::uint32_t v = 0; v < s.node.size(); ++v) {
    if (pressed[v] || h <= 0) {
      to[v] = v;
      continue;
    }
    const Vec3& x = X[s.node[v]];
    const std::array<long, 3> cell{std::lround(std::floor(x[0] / h)), std::lround(std::floor(x[1] / h)), std::lround(std::floor(x[2] / h))};
    to[v] = representative.try_emplace(cell, v).first->second;
  }
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < s.faces.size(); ++i) {
    const auto& t = s.faces[i];
    if (to[t[0]] != to[t[1]] && to[t[1]] != to[t[2]] && to[t[0]] != to[t[2]]) kept.push_back(i);
  }
  return kept;
}

// Bytes of the data files for V vertices, F faces and the states (base64 of floats: 16/3 per value).
std::size_t data_bytes(std::size_t V, std::size_t F, std::size_t states) {
  const std::size_t model = 3 * V + V + 3 * F + 2 * F, per_state = 3 * V + 2 * V + F;
  return (model + per_state * states) * 16 / 3 + 4096 * (states + 1);
}

}  // namespace

namespace {

// The history curves the page plots, at most ~2 x kBuckets rows: per bucket of rows the one with
// the largest force and the one with the largest peak pressure, so no spike is lost.
nlohmann::json history_json(const History& h) {
  constexpr std::size_t kBuckets = 1500;
  nlohmann::json j = nlohmann::json::object();
  if (!h.has(hc::time.name)) return j;
  const std::size_t n = h.rows();
  const std::vector<const char*> names{hc::time.name, hc::contact_force.name, hc::contact_area.name, hc::peak_pressure.name,
                                       hc::peak_step_pressure.name};
  std::vector<std::size_t> rows;
  const std::size_t bucket = std::max<std::size_t>(1, (n + kBuckets - 1) / kBuckets);
  auto largest = [&](const char* column, std::size_t from, std::size_t to) {
    if (!h.has(column)) return from;
    const auto& c = h.column(column);
    return static_cast<std::size_t>(std::max_element(c.begin() + static_cast<long>(from), c.begin() + static_cast<long>(to)) - c.begin());
  };
  for (std::size_t from = 0; from < n; from += bucket) {
    const std::size_t to = std::min(n, from + bucket);
    rows.push_back(from);
    rows.push_back(largest(hc::contact_force.name, from, to));
    rows.push_back(largest(hc::peak_pressure.name, from, to));
  }
  if (n) rows.push_back(n - 1);
  std::sort(rows.begin(), rows.end());
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  for (const char* name : names) {
    if (!h.has(name)) continue;
    std::vector<double> v;
    for (std::size_t r : rows) v.push_back(h.column(name)[r]);
    j[name] = v;
  }
  return j;
}

nlohmann::json field_json(const char* label, const char* unit, double scale, double cap, const Peak& peak, const std::vector<Frame>& frames,
                          const char* cap_rule) {
  return {{"label", label}, {"unit", unit}, {"scale", scale}, {"cap", cap}, {"cap_rule", cap_rule}, {"peak", peak.json(frames)}};
}

// The grasp's table for the page: the handle's load per region (Summary::Grasp, from run.json) and
// the unrolled map's picture when tactus-post drew it; null without a grasp.
nlohmann::json grasp_json(const Summary& summary) {
  const Summary::Grasp& g = summary.grasp;
  if (!g.on) return nullptr;
  nlohmann::json regions = nlohmann::json::array();
  for (const Summary::GripShare& s : g.regions)
    regions.push_back({{"name", s.name},
                       {"digit", s.digit},
                       {"force_N", s.force},
                       {"share", s.share},
                       {"area_m2", s.area},
                       {"peak_pressure_Pa", s.peak_pressure},
                       {"averaged_peak_pressure_Pa", s.averaged_peak_pressure}});
  const bool map = std::find(summary.pictures.begin(), summary.pictures.end(), "grip_map.png") != summary.pictures.end();
  return {{"handle", g.handle},
          {"target_N", g.target},
          {"final_grip_N", g.final_grip},
          {"quasi_static", g.quasi_static},
          {"sensor_area_m2", g.sensor_area},
          {"regions", regions},
          {"grip_map", map ? nlohmann::json("grip_map.png") : nlohmann::json(nullptr)}};
}

nlohmann::json model_json(const Results& r, const Summary& summary, const Scan& scan, const std::vector<std::size_t>& shown, double cluster) {
  const Surface& s = scan.surface;
  std::vector<std::uint32_t> node_id(s.node.size()), faces, face_tet, face_body;
  std::vector<float> X;
  for (std::size_t v = 0; v < s.node.size(); ++v) {
    node_id[v] = s.node[v] + 1;
    for (double c : scan.X[s.node[v]]) X.push_back(static_cast<float>(c));
  }
  const nlohmann::json run = nlohmann::json::parse(r.run_json, nullptr, false);
  for (std::size_t i : shown) {
    for (std::uint32_t v : s.faces[i]) faces.push_back(v);
    face_tet.push_back(s.face_tet[i] + 1);
    face_body.push_back(scan.tet_body[s.face_tet[i]]);
  }
  nlohmann::json states = nlohmann::json::array();
  for (std::size_t k : scan.states) states.push_back({{"time", r.frames[k].time}, {"file", r.frames[k].file.filename().string()}});
  nlohmann::json at_outputs = nlohmann::json::array();
  if (run.is_object() && run.contains("contact") && run["contact"].contains("at_outputs")) at_outputs = run["contact"]["at_outputs"];
  const double pressure_cap = pressure_scale_cap(scan.pressed);
  return {{"format", "tactus-report 1"},
          {"folder", r.folder.string()},
          {"status", run.is_object() && run.contains("status") ? run["status"] : nlohmann::json("unknown")},
          {"bodies", r.bodies},
          {"materials", r.materials},
          {"states", states},
          {"missing", scan.missing},
          {"vertices", s.node.size()},
          {"node_id", base64(node_id)},
          {"reference", base64(X)},
          {"faces", base64(faces)},
          {"face_tet", base64(face_tet)},
          {"face_body", base64(face_body)},
          {"surface_faces", s.faces.size()},
          {"faces_shown", shown.size()},
          {"cluster_size", cluster},
          {"fields",
           {{"pressure", field_json("contact pressure", "MPa", 1e-6, pressure_cap, scan.pressure_peak, r.frames,
                                    "99.5 % of the pressed area of all outputs lies below it")},
            {"von_mises", field_json("von Mises stress", "MPa", 1e-6, scan.stress.cap(), scan.stress_peak, r.frames,
                                     "99.5 % of the tets' volume over all outputs lies below it")},
            {"displacement", field_json("displacement |u|", "mm", 1e3, scan.displacement_peak.value, scan.displacement_peak, r.frames,
                                        "the largest over all outputs")}}},
          {"history", history_json(r.history)},
          {"at_outputs", at_outputs},
          {"grasp", grasp_json(summary)}};
}

// The pressed nodes of one output: id, current position, pressure, friction traction, tributary
// area (the solver's contact_area), body and, for a grasp, the hand region.
std::string pressure_csv(const Surface& s, const StateFields& f, const std::vector<std::string>& bodies,
                         const std::vector<std::uint32_t>& vertex_body, const std::vector<std::string>& vertex_region) {
  std::ostringstream o;
  o << std::setprecision(9) << "node_id,x_m,y_m,z_m,pressure_Pa,traction_x_Pa,traction_y_Pa,traction_z_Pa,area_m2,body,region\n";
  for (std::size_t v = 0; v < s.node.size(); ++v) {
    if (!(f.pressure_pa[v] > 0)) continue;
    const Vec3 &x = f.position[v], &t = f.traction[v];
    const std::uint32_t b = vertex_body[v];
    o << s.node[v] + 1 << ',' << x[0] << ',' << x[1] << ',' << x[2] << ',' << f.pressure_pa[v] << ',' << t[0] << ',' << t[1] << ',' << t[2] << ','
      << f.area[v] << ',' << (b < bodies.size() ? bodies[b] : std::to_string(b)) << ',' << vertex_region[v] << '\n';
  }
  return o.str();
}

// The surface vertex nearest to each probe point in the reference configuration.
std::vector<std::size_t> probe_vertices(const Surface& s, const std::vector<Vec3>& X, const std::vector<Vec3>& probes) {
  std::vector<std::size_t> nearest;
  if (s.node.empty()) return nearest;
  for (const Vec3& q : probes) {
    std::size_t best = 0;
    for (std::size_t v = 1; v < s.node.size(); ++v)
      if (norm(X[s.node[v]] - q) < norm(X[s.node[best]] - q)) best = v;
    nearest.push_back(best);
  }
  return nearest;
}

std::vector<std::uint32_t> vertex_bodies(const Surface& s, const std::vector<std::uint32_t>& tet_body) {
  std::vector<std::uint32_t> body(s.node.size(), 0);
  for (std::size_t i = 0; i < s.faces.size(); ++i)
    for (std::uint32_t v : s.faces[i]) body[v] = tet_body[s.face_tet[i]];
  return body;
}

}  // namespace

WebReport write_web_report(const Results& r, const Summary& summary, const fs::path& report, const WebReportOptions& o) {
  WebReport out;
  Scan scan = scan_states(r);
  const Surface& s = scan.surface;
  std::vector<std::size_t> shown(s.faces.size());
  for (std::size_t i = 0; i < shown.size(); ++i) shown[i] = i;
  double cluster = 0;
  if (!s.faces.empty() && data_bytes(s.node.size(), s.faces.size(), scan.states.size()) > o.byte_budget) {
    // Start from the mean edge length and grow the clusters until the data fits.
    double edges = 0;
    for (const auto& t : s.faces) edges += norm(scan.X[s.node[t[0]]] - scan.X[s.node[t[1]]]);
    cluster = edges / static_cast<double>(s.faces.size());
    do {
      cluster *= 1.5;
      shown = cluster_faces(s, scan.X, scan.ever_pressed, cluster);
    } while (data_bytes(s.node.size(), shown.size(), scan.states.size()) > o.byte_budget && shown.size() > 1000);
    std::ostringstream note;
    note << "interactive report: " << s.faces.size() << " surface triangles would take over " << (o.byte_budget >> 20)
         << " MB; the surface that never touches is coarsened to " << shown.size() << " (clusters of " << cluster * 1e3 << " mm)";
    log::warn(note.str());
  }
  out.surface_faces = s.faces.size(), out.faces_shown = shown.size(), out.missing = scan.missing;
  if (o.page) fs::create_directories(report / "data");
  auto put = [&](const std::string& name, std::string_view text) {
    write_file(report / name, text);
    out.files.push_back(name);
    out.bytes += text.size();
  };
  if (o.page) put("data/model.js", "tactusModel(" + model_json(r, summary, scan, shown, cluster).dump() + ");\n");
  const std::vector<std::size_t> probes = probe_vertices(s, scan.X, o.probes);
  std::ostringstream probe_rows;
  probe_rows << std::setprecision(9) << "probe,x_m,y_m,z_m,node_id,distance_m,time_s,pressure_Pa\n";
  const std::vector<std::uint32_t> vertex_body = vertex_bodies(s, scan.tet_body);
  // The states again, one file each (the page loads them one by one; nothing holds them all).
  for (std::size_t j = 0; j < scan.states.size(); ++j) {
    const std::size_t k = scan.states[j];
    const StateFields f = state_fields(load_state(r.frames[k].file), k, s, nullptr, r.frames[k].file.string());
    if (f.has_pressure && std::any_of(f.pressure_pa.begin(), f.pressure_pa.end(), [](double q) { return q > 0; }))
      put("pressure_" + ms(r.frames[k].time) + "ms.csv", pressure_csv(s, f, r.bodies, vertex_body, scan.vertex_region));
    for (std::size_t q = 0; q < probes.size(); ++q) {
      const Vec3& at = o.probes[q];
      probe_rows << q + 1 << ',' << at[0] << ',' << at[1] << ',' << at[2] << ',' << s.node[probes[q]] + 1 << ','
                 << norm(scan.X[s.node[probes[q]]] - at) << ',' << r.frames[k].time << ',' << f.pressure_pa[probes[q]] << '\n';
    }
    if (!o.page) continue;
    std::vector<float> per_face;
    for (std::size_t i : shown) per_face.push_back(f.von_mises_face[i]);
    const nlohmann::json j_state = {{"displacement", base64(f.displacement)},
                                    {"pressure", f.has_pressure ? nlohmann::json(base64(f.pressure)) : nlohmann::json(nullptr)},
                                    {"von_mises_nodal", base64(f.von_mises_nodal)},
                                    {"von_mises_tet", base64(per_face)}};
    std::ostringstream name;
    name << "data/state_" << std::setw(4) << std::setfill('0') << j << ".js";
    put(name.str(), "tactusState(" + std::to_string(j) + ", " + j_state.dump() + ");\n");
  }
  if (!probes.empty()) put("probes.csv", probe_rows.str());
  if (o.page)
    for (const EmbeddedFile& a : web_report_assets()) put(a.name, a.text);
  return out;
}

}  // namespace tactus::postproc
