// history.csv: one table of columns (names from core/contracts.hpp), which writes both the header
// and every row, so the two can never drift apart.
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>

#include "results.hpp"
#include "tactus/core/contracts.hpp"
#include "tactus/core/error.hpp"
#include "tactus/core/file_io.hpp"

namespace tactus::solver {

namespace {

namespace h = contracts::history;

double magnitude(const Vec3& f) { return std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]); }

struct Column {
  const contracts::ColumnSpec* spec;
  double (*value)(const HistoryRow&);
};

// In the order of contracts::history::all (checked at compile time below).
constexpr std::array<Column, h::all.size()> kColumns{{
    {&h::step, [](const HistoryRow& r) { return static_cast<double>(r.step); }},
    {&h::time, [](const HistoryRow& r) { return r.time; }},
    {&h::dt, [](const HistoryRow& r) { return r.dt; }},
    {&h::kinetic_energy, [](const HistoryRow& r) { return r.energy->kinetic; }},
    {&h::internal_energy, [](const HistoryRow& r) { return r.energy->internal; }},
    {&h::damping_work, [](const HistoryRow& r) { return r.energy->damping_work; }},
    {&h::external_work, [](const HistoryRow& r) { return r.energy->external_work; }},
    {&h::contact_work_normal, [](const HistoryRow& r) { return r.energy->contact_normal_work; }},
    {&h::contact_work_friction, [](const HistoryRow& r) { return r.energy->contact_friction_work; }},
    {&h::energy_balance_error, [](const HistoryRow& r) { return r.energy->balance_error(); }},
    {&h::critical_step, [](const HistoryRow& r) { return r.critical_step; }},
    {&h::contact_force, [](const HistoryRow& r) { return magnitude(r.contact->force); }},
    {&h::contact_force_x, [](const HistoryRow& r) { return r.contact->force[0]; }},
    {&h::contact_force_y, [](const HistoryRow& r) { return r.contact->force[1]; }},
    {&h::contact_force_z, [](const HistoryRow& r) { return r.contact->force[2]; }},
    {&h::contact_normal_force, [](const HistoryRow& r) { return r.contact->normal_force; }},
    {&h::contact_area, [](const HistoryRow& r) { return r.contact->area; }},
    {&h::peak_pressure, [](const HistoryRow& r) { return r.contact->peak_pressure; }},
    {&h::peak_pressure_x, [](const HistoryRow& r) { return r.peak_at[0]; }},
    {&h::peak_pressure_y, [](const HistoryRow& r) { return r.peak_at[1]; }},
    {&h::peak_pressure_z, [](const HistoryRow& r) { return r.peak_at[2]; }},
    {&h::peak_step_pressure, [](const HistoryRow& r) { return r.contact->peak_step_pressure; }},
    {&h::contact_nodes, [](const HistoryRow& r) { return static_cast<double>(r.contact->active); }},
    {&h::stick_nodes, [](const HistoryRow& r) { return static_cast<double>(r.contact->sticking); }},
    {&h::slip_nodes, [](const HistoryRow& r) { return static_cast<double>(r.contact->slipping); }},
    {&h::uzawa_iterations, [](const HistoryRow& r) { return static_cast<double>(r.contact->iterations); }},
}};

constexpr bool columns_follow_the_contract() {
  for (std::size_t k = 0; k < kColumns.size(); ++k)
    if (kColumns[k].spec != h::all[k]) return false;
  return true;
}
static_assert(columns_follow_the_contract(), "history.csv columns must follow contracts::history::all");

}  // namespace

HistoryWriter::HistoryWriter(const std::filesystem::path& file, const std::vector<BoundaryReactionSpec>& boundaries,
                             const std::vector<std::string>& mass_scaled_bodies, std::uintmax_t resume_at,
                             const std::vector<std::string>& rigid_bodies, const JointDrive* joints, const GripRegions* regions)
    : file_(file),
      boundaries_(boundaries.size()),
      mass_scaled_bodies_(mass_scaled_bodies.size()),
      rigid_bodies_(rigid_bodies.size()),
      joints_(joints ? joints->skeleton().joints.size() : 0),
      grasp_(joints && joints->grasp()),
      regions_(regions ? regions->names().size() : 0),
      digits_(regions ? regions->digits().size() : 0) {
  if (resume_at != kNew) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (ec || size < resume_at)
      throw InputError(file.string(), "", std::to_string(resume_at) + " bytes of history (as when the checkpoint was written)",
                       ec ? "no file" : std::to_string(size) + " bytes");
    std::filesystem::resize_file(file, resume_at, ec);  // the rows after the checkpoint go: they are computed again
    if (ec) throw WriteError(file.string(), "cannot cut the history back to the checkpoint (" + ec.message() + ")");
    out_ = std::make_unique<FileWriter>(file, FileWriter::Mode::append);
    return;
  }
  out_ = std::make_unique<FileWriter>(file);
  std::string header;
  for (std::size_t k = 0; k < kColumns.size(); ++k) header.append(k ? "," : "").append(kColumns[k].spec->name);
  for (const auto& b : boundaries)
    for (const auto* family : h::per_boundary)
      for (const char* axis : {"_x", "_y", "_z"}) header.append(",").append(family->prefix).append(b.name).append(axis);
  for (const auto& body : mass_scaled_bodies) header.append(",").append(h::added_mass.prefix).append(body);
  for (const auto& body : rigid_bodies)
    for (const auto* family : h::per_rigid_body)
      for (const char* axis : {"_x", "_y", "_z"}) header.append(",").append(family->prefix).append(rigid_column_name(body)).append(axis);
  if (joints)
    for (const SkeletonJoint& j : joints->skeleton().joints) header.append(",").append(h::joint_flexion.prefix).append(rigid_column_name(j.name));
  if (grasp_)
    for (const auto* column : h::grasp) header.append(",").append(column->name);
  if (regions) {
    for (const auto* family : h::per_grip_region)
      for (const std::string& r : regions->names()) header.append(",").append(family->prefix).append(r);
    for (const std::string& d : regions->digits()) header.append(",").append(h::digit_force.prefix).append(d);
  }
  out_->write(header + '\n');
}

namespace {

// The shortest text that reads back as the same double (std::to_chars: exact round trip, about
// ten times faster than a stream at 17 digits; a history row of a hand with 27 rigid bones has
// ~500 values and is written every step).
void append_value(std::string& line, double v) {
  char text[32];
  const auto r = std::to_chars(text, text + sizeof text, v);
  line += ',';
  line.append(text, r.ptr);
}

}  // namespace

void HistoryWriter::write(const HistoryRow& row) {
  std::string& line = line_;  // (a member: its capacity is kept between rows)
  line.clear();
  for (std::size_t k = 0; k < kColumns.size(); ++k) append_value(line, kColumns[k].value(row));  // (counts print as integers: "3")
  for (std::size_t b = 0; b < boundaries_; ++b) {                                                // in the order of h::per_boundary: reaction, moment
    for (int c = 0; c < 3; ++c) append_value(line, row.reactions ? row.reactions->force[3 * b + static_cast<std::size_t>(c)] : 0.0);
    for (int c = 0; c < 3; ++c) append_value(line, row.reactions ? row.reactions->moment[3 * b + static_cast<std::size_t>(c)] : 0.0);
  }
  for (std::size_t b = 0; b < mass_scaled_bodies_; ++b) append_value(line, row.added_mass ? (*row.added_mass)[b] : 0.0);
  for (std::size_t b = 0; b < rigid_bodies_; ++b) {  // in the order of h::per_rigid_body
    const RigidBody& r = (*row.rigid)[b];
    const Vec3d values[6] = {r.centre,         r.momentum / r.mass, r.rotation_vector(), r.angular_velocity_of(r.angular_momentum),
                             r.reaction_force, r.reaction_moment};
    for (const Vec3d& v : values)
      for (int c = 0; c < 3; ++c) append_value(line, v[c]);
  }
  for (std::size_t j = 0; j < joints_; ++j) append_value(line, row.joints->flexion_at_step()[j] * 180 / M_PI);
  if (grasp_)  // in the order of h::grasp
    for (double v : {row.joints->grip_force(), row.joints->grip_target(), row.joints->drive_scale()}) append_value(line, v);
  if (regions_ > 0) {  // in the order of h::per_grip_region, then the digits
    for (const std::vector<double>* values : {&row.regions->force(), &row.regions->area(), &row.regions->peak_pressure()})
      for (double v : *values) append_value(line, v);
    for (double v : row.regions->digit_force()) append_value(line, v);
  }
  line += '\n';
  out_->write(std::string_view(line).substr(1));  // without the first value's comma
}

std::uintmax_t HistoryWriter::flush() {
  out_->flush();
  return out_->size();
}

std::string rigid_column_name(const std::string& name) {
  std::string out;
  for (char ch : name) {
    if (ch == '#') continue;
    out += (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-') ? ch : '_';
  }
  std::string squeezed;  // one _ for a run of them
  for (char ch : out)
    if (ch != '_' || squeezed.empty() || squeezed.back() != '_') squeezed += ch;
  return squeezed;
}

void HistoryWriter::close() { out_->close(); }

}  // namespace tactus::solver
