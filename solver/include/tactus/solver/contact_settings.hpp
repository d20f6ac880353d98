#pragma once
// What contact takes ([[contact]] entries and [contact_solver] of scenario.toml, or set in code):
// plain structs, and the choice of each entry's method (contact.hpp builds the pairs from them).
#include <array>
#include <cstddef>
#include <optional>
#include <string>

#include "tactus/core/vec3.hpp"

namespace tactus::solver {

// node_to_surface: each slave node on its closest master point; mortar: segment-to-segment
// integrals of the slave surface; automatic: contact_method() chooses.
enum class ContactMethod { automatic, node_to_surface, mortar };
const char* contact_method_name(ContactMethod m);

// [[contact]]: slave nodes of one body's surface against another body's surface or a rigid plane.
struct ContactSpec {
  std::string slave_body, slave_surface, master_body, master_surface;
  std::optional<std::array<Vec3, 2>> plane;  // point, outward normal (rigid plane master)
  double friction = 0;                       // Coulomb coefficient mu
  bool two_pass = false;                     // also the master's nodes against the slave surface
  // Mortar only: also the master's convex edge and corner nodes (faces meeting at more than
  // kEdgePassAngleDeg) against the slave surface, node to surface (surfaces.cpp).
  bool edge_pass = true;
  ContactMethod method = ContactMethod::automatic;
};

// The method of a [[contact]] entry: its own, or by default mortar (segment-to-segment integrals of
// the slave surface: a pressure field that passes the contact patch test) for a deformable master
// of another surface in one pass, and node_to_surface for self-contact, a rigid plane and two_pass
// (mortar has no second pass: its rows already weigh the master's nodes).
ContactMethod contact_method(const ContactSpec& c);
// A [[contact]] entry whose master is its own slave surface (skin on skin).
bool is_self_contact(const ContactSpec& c);

// [contact_solver]: the Uzawa iterations and the search.
struct ContactSettings {
  double tolerance = 1e-6;  // stop when max |dr| <= tolerance * max |r| over the contact nodes
  int max_iterations = 200;
  double search_factor = 0.5;  // search distance and penetration band, in mean master edges
  // Verlet skin of the node-to-surface search, in mean master edges: candidate triangles are
  // gathered within band + skin and kept until a node has moved half the skin (0: every step).
  double verlet_skin = 0.5;
  // The reported contact pressure is the per-step pressure r_n / A averaged over an exponential
  // window of tau = max(pressure_window, 10 x the initial critical step), s.
  double pressure_window = 1e-5;
  // The area of the pressure "sensor": at each output the reported pressure field is also averaged
  // over every disc of this area on the slave surfaces (centred on a contact node), and the largest
  // such average is reported. Unlike a node's value it does not grow when the mesh is refined at
  // an edge or corner load, m^2.
  double pressure_average_area = 25e-6;
  // A row found deeper inside its master than this speed times the step (a penetration the last
  // step did not make: a node that slid back over a master's edge, a row that just appeared) is
  // pushed out at this speed instead of in one step, m/s.
  double recovery_speed = 1.0;
  // The Uzawa sweep in slabs: the rows are cut into at most this many slabs along the contact's
  // longest extent, the even slabs swept in parallel (each in row order, Gauss-Seidel), then the
  // odd ones, then the rows shared between slabs of one parity in order (contact/bipotential.cpp).
  // The slabs do not depend on the thread count (the same bits on any number of threads); 1: one
  // sweep in row order. At most one slab per kMinRowsPerSweepBlock rows: a slab's sweep (~0.1 us
  // a row) must outweigh the fork and join of the threads around it (a few us).
  int sweep_blocks = 16;
  static constexpr std::size_t kMinRowsPerSweepBlock = 256;
};

}  // namespace tactus::solver
