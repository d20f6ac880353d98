// Solver benchmarks (issue: solver core):
//  throughput  internal-force (stress pass) tet updates per second for neo_hookean, hgo (each as
//              standard and as average-nodal-pressure tets, the J pass included) and
//              linear_elastic, 1 and 2 threads, at ~10k, 100k and 1M tets, on meshes whose
//              numbering is shuffled as a mesher without locality ordering could leave it,
//              with and without tactus' Morton reordering; the vector kernel (four tets per SIMD
//              register) and the scalar one (one tet at a time, same formulas) timed alternately,
//              medians of --rounds timings, and their ratio; lscpu's threads per core; plus bytes
//              per tet of solver state.
//  cube        the whole-run case: 0.1 m cube, 20^3 cells x 6 tets = 48,000 tets, neo_hookean
//              mu = 3 kPa, bulk 50 kPa, rho 1000, bottom fixed, top pushed down 10 % over 2,000
//              steps of dt = 1e-4 s, mass damping 50 /s, timed end to end (mesh file to results).
//  contact     contact time per step against surface size: two slabs (n x n x 1 cells each)
//              pressed face to face, every slave node in contact, mu = 0.3; detection + Uzawa
//              per step against the stress pass of the same model, 2 threads; each size with
//              each --sweep-blocks setting (the ordered sweep, 1, and parallel slabs), side by side.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "tactus/core/cli.hpp"
#include "tactus/core/error.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"
#include "tactus/solver/run.hpp"

using namespace tactus;
using namespace tactus::solver;
using Clock = std::chrono::steady_clock;

namespace {

// name: a law, or "<law>/anp" and "<law>/standard" for a formulation other than its default
// (hgo with k = 1e8 runs as ANP by default); "<law>/anp<s>" sets the pressure smoothing passes;
// a trailing "+nofloor" turns the ANP volume floor off (volume_floor = 0), to time its check.
Material bench_material(const std::string& tagged) {
  const bool no_floor = tagged.ends_with("+nofloor");
  const std::string label = no_floor ? tagged.substr(0, tagged.size() - 8) : tagged;
  const std::string name = label.substr(0, label.find('/'));
  MaterialValues v;
  if (no_floor) v.numbers["volume_floor"] = 0.0;
  if (name == "neo_hookean") v.numbers = {{"mu", 3000.0}, {"bulk", 50000.0}, {"density", 1000.0}};
  if (name == "linear_elastic") v.numbers = {{"E", 1e9}, {"nu", 0.3}, {"density", 2000}};
  if (name == "hgo") {
    v.numbers = {{"c1", 10206.9}, {"k1", 1.7}, {"k2", 882.847}, {"k", 1e8}, {"density", 1050}};
    v.vectors["fibres"] = {Vec3{0.8660254, 0.5, 0}, Vec3{0.8660254, -0.5, 0}};
  }
  if (label.find('/') != std::string::npos) {
    std::string formulation = label.substr(label.find('/') + 1);
    if (formulation.size() > 3 && formulation.starts_with("anp")) {
      const std::string passes = formulation.substr(3);
      if (passes.find_first_not_of("0123456789") != std::string::npos)
        throw InputError("--materials", label, "<law>/anp<smoothing passes> (a whole number after \"anp\")", label);
      v.numbers["pressure_smoothing"] = std::stod(passes);
      formulation = "anp";
    }
    v.strings["formulation"] = formulation;
  }
  return Material::make(name, v);
}

// A deformed state: a smooth 3 % stretch/shear field with a little noise, so hgo fibres engage.
std::vector<double> deformed_state(const Model& m) {
  std::vector<double> u(3 * m.num_nodes);
  for (std::size_t i = 0; i < m.num_nodes; ++i) {
    const double* X = &m.X[3 * i];
    u[3 * i] = 0.03 * X[0] + 0.01 * X[1] + 1e-4 * std::sin(1e3 * X[2]);
    u[3 * i + 1] = -0.01 * X[1] + 0.005 * X[2];
    u[3 * i + 2] = -0.01 * X[2] + 1e-4 * std::cos(1e3 * X[0]);
  }
  return u;
}

// Stress-pass rates (tet updates per second) of the vector and the scalar kernels on the same
// model, and of the vector kernel with the element step estimate alone (no nodal step bound),
// each the median of `rounds` timings of >= 0.3 s taken alternately (side by side, so that a
// noisy neighbour slows all three).
struct Rates {
  double vector, scalar, element_only;
};
Rates updates_per_second(const Model& m, int threads, int rounds) {
  const auto u = deformed_state(m);
  std::vector<double> v(u.size(), 0.0), f(u.size());
  InternalForces vector(m, 0.0, threads), scalar(m, 0.0, threads), element_only(m, 0.0, threads);
  scalar.set_vectorised(false);
  element_only.set_nodal_step_bound(nullptr);
  auto time = [&](InternalForces& forces) {
    forces.compute(u.data(), v.data(), f.data());  // warm-up
    std::size_t passes = 0;
    const auto t0 = Clock::now();
    double elapsed = 0;
    while (elapsed < 0.3 || passes < 3) {
      forces.compute(u.data(), v.data(), f.data());
      ++passes;
      elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    }
    return static_cast<double>(passes * m.num_elements) / elapsed;
  };
  std::vector<double> rv, rs, re;
  for (int k = 0; k < rounds; ++k) rv.push_back(time(vector)), rs.push_back(time(scalar)), re.push_back(time(element_only));
  auto median = [](std::vector<double> x) {
    std::sort(x.begin(), x.end());
    return x[x.size() / 2];
  };
  return {median(rv), median(rs), median(re)};
}

// lscpu's "Thread(s) per core" (2: the two threads may share one core's SIMD units).
std::string threads_per_core() {
  std::string out = "unknown";
  if (FILE* p = popen("lscpu 2>/dev/null", "r")) {
    char line[512];
    while (std::fgets(line, sizeof line, p))
      if (std::string l = line; l.rfind("Thread(s) per core:", 0) == 0) out = l.substr(l.find(':') + 1), out.erase(0, out.find_first_not_of(" \t"));
    pclose(p);
    if (!out.empty() && out.back() == '\n') out.pop_back();
  }
  return out;
}

void throughput(const std::vector<int>& sizes, const std::vector<std::string>& materials, int rounds) {
  std::printf("lscpu threads per core: %s\n", threads_per_core().c_str());
  std::printf("%-15s %9s %8s %7s %12s %12s %8s %14s %18s\n", "material", "tets", "order", "threads", "vector M/s", "scalar M/s", "ratio",
              "ns/tet (vec)", "ns/tet (no nodal)");
  for (int n : sizes) {
    TetMesh mesh = samples::make_box_mesh(n, n, n, 0.1, 0.1, 0.1);
    samples::perturb_interior_nodes(mesh, 0.1 / n, 0.2, 1);
    samples::shuffle_numbering(mesh, 2);
    for (const std::string& mat : materials) {
      for (bool reorder : {false, true}) {
        if (!reorder && mat.find('/') != std::string::npos) continue;  // formulations: Morton order only
        const Model m = build_model(mesh, bench_material(mat), mat, {0, 0, 0}, reorder);
        for (int threads : {1, 2}) {
          const auto [vec, sca, element_only] = updates_per_second(m, threads, rounds);
          std::printf("%-15s %9zu %8s %7d %12.2f %12.2f %8.2f %14.2f %18.2f\n", mat.c_str(), m.num_elements, reorder ? "morton" : "shuffled", threads,
                      vec / 1e6, sca / 1e6, vec / sca, 1e9 / vec, 1e9 / element_only);
          std::fflush(stdout);
        }
      }
    }
    const Model m = build_model(mesh, bench_material("hgo"));
    RunSpec run;
    run.end_time = 1;
    run.threads = 2;
    const ExplicitSolver solver(m, run, DampingSpec{});
    std::printf("memory at %zu tets: model %.0f B/tet + integrator %.0f B/tet = %.0f B/tet (%zu nodes)\n", m.num_elements,
                static_cast<double>(m.memory_bytes()) / static_cast<double>(m.num_elements),
                static_cast<double>(solver.memory_bytes()) / static_cast<double>(m.num_elements),
                static_cast<double>(m.memory_bytes() + solver.memory_bytes()) / static_cast<double>(m.num_elements), m.num_nodes);
  }
  std::printf("rates: medians of %d alternating timings; vector = %d tets per SIMD lane group, scalar = one tet at a time (same formulas)\n", rounds,
              InternalForces::lanes());
}

void cube(const std::filesystem::path& work) {
  std::filesystem::create_directories(work);
  write_msh(work / "cube.msh", samples::make_box_mesh(20, 20, 20, 0.1, 0.1, 0.1));
  Scenario sc;
  sc.file = work / "cube.toml";
  sc.run.end_time = 0.2;
  sc.run.time_step = 1e-4;
  sc.run.output_times = {0.1, 0.2};
  sc.damping.alpha = 50;
  sc.materials["rubber"] = MaterialInstance{"rubber", "neo_hookean", {{{"mu", 3000.0}, {"bulk", 50000.0}, {"density", 1000.0}}, {}}};
  BodySpec body;
  body.name = "cube";
  body.mesh = work / "cube.msh";
  body.materials["*"] = "rubber";
  sc.bodies.push_back(body);
  sc.boundaries.push_back(BoundarySpec{"cube", "zmin", {}, solver::BoundaryType::fixed, {0, 0, 0}, {true, true, true}, {0, 0, 0}, "", "", {0, 0, 0}});
  sc.boundaries.push_back(
      BoundarySpec{"cube", "zmax", {}, solver::BoundaryType::velocity, {0, 0, -0.01 / 0.2}, {true, true, true}, {0, 0, 0}, "", "", {0, 0, 0}});
  const auto t0 = Clock::now();
  const RunSummary s = run_simulation(sc, work / "results");
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  std::printf("cube: 48000 tets, %zu steps, wall %.2f s (%.2f M tet-steps/s end to end), energy balance error %.2e relative\n", s.steps, wall,
              48000.0 * static_cast<double>(s.steps) / wall / 1e6, s.max_relative_balance_error);
}

void contact_scaling(const std::vector<int>& sizes, const std::vector<int>& sweep_blocks) {
  std::printf("%9s %9s %11s %9s %7s %12s %12s %8s %10s %10s\n", "master_tri", "slave_nod", "tets", "active", "slabs", "contact_ms", "stress_ms",
              "ratio", "iterations", "step_ms");
  for (int n : sizes)
    for (int blocks : sweep_blocks) {
      TetMesh lower = samples::make_box_mesh(n, n, 1, 0.1, 0.1, 0.01);
      const TetMesh upper = samples::make_box_mesh(n, n, 1, 0.1, 0.1, 0.01, {0, 0, 0.01});
      samples::append_mesh(lower, upper, 100, "_upper");
      Model m = build_model(lower, bench_material("linear_elastic"));
      ContactPair pair;
      pair.name = "slabs";
      pair.friction = 0.3;
      set_master_surface(pair, m, surface_triangles(m, 16), "lower zmax");
      set_slave_surface(pair, m, surface_triangles(m, 115));  // upper zmin
      m.contact_pairs.push_back(pair);
      if (const char* it = std::getenv("TACTUS_BENCH_UZAWA_ITERATIONS")) m.contact_settings.max_iterations = std::atoi(it);
      m.contact_settings.sweep_blocks = blocks;
      for (std::size_t i = 0; i < m.num_nodes; ++i)
        if (m.X[3 * i + 2] > 0.01 - 1e-9) m.initial_velocity[3 * i + 2] = -0.5, m.initial_velocity[3 * i] = 0.2;
      RunSpec run;
      run.end_time = 1;
      run.threads = 2;
      ExplicitSolver solver(m, run, DampingSpec{});
      std::size_t active = 0;
      int iterations = 0, slabs = 1;
      const int steps = 20;
      double contact0 = 0, stress0 = 0, ahead0 = 0;
      for (int k = 0; k < steps + 2; ++k) {
        if (k == 2)
          contact0 = solver.contact_seconds(), stress0 = solver.stress_seconds(), ahead0 = solver.detection_ahead_seconds();  // after warm-up
        solver.advance_velocity();  // free update + contact (detection + Uzawa)
        solver.advance_position();  // position update + stress pass
        active = std::max(active, solver.contact_report().active);
        iterations = std::max(iterations, solver.contact_report().iterations);
        slabs = solver.contact_report().sweep_blocks;
      }
      // The next step's detection runs inside the stress pass (on one thread): counted as contact
      // here, and the pass's wall time (which hides part of it) stays the stress time.
      const double ahead_s = solver.detection_ahead_seconds() - ahead0;
      const double contact_s = solver.contact_seconds() - contact0 + ahead_s, stress_s = solver.stress_seconds() - stress0;
      std::printf("%9zu %9zu %11zu %9zu %7d %12.3f %12.3f %8.3f %10d %10.3f\n", pair.master->triangles().size() / 3, pair.slave_nodes.size(),
                  m.num_elements, active, slabs, 1e3 * contact_s / steps, 1e3 * stress_s / steps, contact_s / stress_s, iterations,
                  1e3 * (contact_s - ahead_s + stress_s) / steps);
      std::fflush(stdout);
    }
  std::printf(
      "per step: contact_ms = detection (run on one thread during the stress pass) + Uzawa (Gauss-Seidel, in row order or in parallel slabs: "
      "slabs, from --sweep-blocks); stress_ms = the "
      "stress pass's wall time (2 threads, the detection's overlap included); step_ms = the wall time of both\n");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tactus-bench-solver: solver throughput, memory and whole-run benchmarks", "tactus-bench-solver"};
  cli::CommonOptions common;
  cli::add_common_options(app, common, "");
  std::vector<int> sizes{12, 26, 55};  // 6 n^3 tets: 10,368 / 105,456 / 998,250
  std::string work = "out/bench";
  std::vector<std::string> materials{"neo_hookean", "neo_hookean/anp", "hgo/standard", "hgo/anp", "linear_elastic"};
  int rounds = 5;
  auto* tp = app.add_subcommand("throughput", "stress-pass throughput (vector and scalar kernels) and memory per tet");
  tp->add_option("--cells", sizes, "cells per box edge (6 n^3 tets)")->capture_default_str();
  tp->add_option("--materials", materials, "laws, or <law>/anp, <law>/anp<smoothing passes> and <law>/standard; +nofloor: the ANP volume floor off")
      ->capture_default_str();
  tp->add_option("--rounds", rounds, "timings per rate (the median is printed)")->capture_default_str()->check(CLI::Range(1, 100));
  auto* cb = app.add_subcommand("cube", "whole-run neo_hookean cube (48,000 tets, 2,000 steps)");
  cb->add_option("--work", work, "folder for the mesh and results")->capture_default_str();
  std::vector<int> contact_sizes{16, 32, 64, 128, 224};  // 2 n^2 master triangles: 512 ... 100,352
  auto* ct = app.add_subcommand("contact", "contact time per step against contact surface size");
  ct->add_option("--cells", contact_sizes, "cells per slab edge (2 n^2 triangles per contact face)")->capture_default_str();
  std::vector<int> sweep_blocks{1, 16};
  ct->add_option("--sweep-blocks", sweep_blocks, "contact_solver.sweep_blocks settings, each run at every size (side by side)")
      ->capture_default_str();
  app.require_subcommand(1);
  return cli::run(app, argc, argv, common, [&] {
    if (tp->parsed()) throughput(sizes, materials, rounds);
    if (cb->parsed()) cube(work);
    if (ct->parsed()) contact_scaling(contact_sizes, sweep_blocks);
  });
}
