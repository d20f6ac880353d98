// Uses the installed libraries: builds a box, computes its critical step, prints the tet count.
#include <cstdio>

#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/explicit.hpp"
#include "tactus/solver/model.hpp"
#include "tactus/solver/model_build.hpp"

int main() {
  using namespace tactus;
  const TetMesh mesh = samples::make_box_mesh(2, 2, 2, 0.01, 0.01, 0.01);
  const solver::Material rubber = solver::Material::make("neo_hookean", {{{"mu", 3000.0}, {"bulk", 50000.0}, {"density", 1000.0}}, {}});
  const solver::Model model = solver::build_model(mesh, rubber);
  solver::RunSpec run;
  run.end_time = 1e-3;
  const solver::ExplicitSolver s(model, run, solver::DampingSpec{});
  std::printf("%zu %g\n", model.num_elements, s.critical_step());
  return model.num_elements == 48 && s.critical_step() > 0 ? 0 : 1;
}
