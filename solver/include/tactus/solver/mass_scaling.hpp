#pragma once
// The masses the explicit integrator steps with, and selective mass scaling: per node the
// model's lumped mass plus what mass scaling added, per dof its inverse and the inverse the
// contact sweep takes (0 on prescribed dofs, whose supports take the reaction). With
// run.minimum_time_step > 0 every tet whose stable step falls below it gets mass until it is met
// (its step grows as the square root of its mass); the added mass is booked per body, with the
// kinetic energy and momentum it brought, so the energy audit (energy.hpp) still closes.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "tactus/core/vec3.hpp"

namespace tactus::solver {

struct Model;
struct StressPassResult;
struct FloorTet;
class InternalForces;
class RigidBodies;

class MassScaling {
 public:
  // floor: run.minimum_time_step (0: off); the masses start as the model's.
  MassScaling(const Model& model, double floor);
  bool on() const { return floor_ > 0; }
  // After a stress pass whose critical step is below the floor: adds to the nodes of every tet
  // the pass raised to meet it (`below`, in tet order: StressPassEngine::raise_to_floor, which
  // raised its mass factor so its step before the safety factor meets the floor) the mass that
  // raise stands for. A rigid body's node gets none (its body's mass is its own, and far larger).
  void scale(const std::vector<FloorTet>& below, const RigidBodies& rigid);
  double floor_squared() const { return floor_ * floor_; }
  // Then the pass's element estimate and critical step become the scaled ones: `smallest`, the
  // smallest step with the raised factors and its tet (StressPassEngine::smallest_scaled_step).
  static void take_scaled_step(StressPassResult& pass, const std::pair<double, std::size_t>& smallest);
  // The first body (model.bodies order) whose added mass exceeds `limit` times its own mass, or -1.
  std::ptrdiff_t body_over(double limit) const;
  // The mass added since the last call, at the velocities v^n (v_old alone on the first step):
  // its kinetic energy 1/2 dm (v^n)^2 into `kinetic`, its momentum dm v^{n-1/2} into
  // added_momentum (the update from v^{n-1/2} conserves the momentum of the new masses, so that
  // is what the added mass brought).
  void book_added(const double* v_old, const double* v_new, bool first, double& kinetic);
  // The nodes whose pending_added is not 0, ascending (the order book_added sums them in), kept by
  // scale and book_added so that neither they nor the ranks' gather of those nodes' velocities scan
  // every node each step.
  const std::vector<std::uint32_t>& raised_nodes() const { return raised_; }
  void forget_added();    // pending_added to 0 (the energy audit's start counts the masses whole)
  void recount_raised();  // raised_nodes() from pending_added (after a checkpoint is read)

  std::vector<double> mass;                      // per node: the model's plus the added, kg
  std::vector<double> inverse_mass;              // per dof
  std::vector<double> contact_inverse_mass;      // per dof, 0 on prescribed dofs
  std::vector<double> pending_added;             // per node, added since the last book_added
  std::vector<double> added_to_body, body_mass;  // per body, kg (empty when off)
  Vec3 added_momentum{0, 0, 0};

 private:
  const Model& model_;
  double floor_;
  std::vector<std::uint32_t> raised_;
};

}  // namespace tactus::solver
