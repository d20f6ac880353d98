// Domain decomposition (solver/decomposition.hpp) on a box of 16 x 16 x 8 Kuhn cells (12,288
// tets, one material). Oracles: the faces between ranks and the halo nodes recounted here
// independently (a face map, a node's set of ranks), the costs summed from the tet counts, the
// atoms the same at every rank count and the parts the same on a second call, and the load
// imbalance within METIS's 3 % tolerance (the bound: 5 %).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <set>

#include "expect_error.hpp"
#include "material_kit.hpp"
#include "tactus/core/error.hpp"
#include "tactus/data_samples/box_mesh.hpp"
#include "tactus/solver/decomposition.hpp"
#include "tactus/solver/internal_force.hpp"
#include "tactus/solver/model.hpp"
#include "temp_dir.hpp"

using namespace tactus;
using namespace tactus::solver;

namespace {

Material box_material() {
  MaterialValues v;
  v.numbers = {{"E", 1e6}, {"nu", 0.3}, {"density", 1000.0}};
  return Material::make("linear_elastic", v);
}

// Two ranks' passes in one process: the exchange that copies into `to`'s received halo slots the
// slots `from` sends, by position (as MPI would deliver them), once `from` has computed.
struct HaloCopy {
  InternalForces *to, *from;
  StressExchange exchange() {
    StressExchange e;
    e.context = this;
    e.finish = [](void* c) {
      auto* k = static_cast<HaloCopy*>(c);
      const HaloSlots &into = k->to->halo()[0], &out_of = k->from->halo()[0];
      for (std::size_t j = 0; j < into.receive.size(); ++j)
        for (std::size_t i = 0; i < InternalForces::kSlotDoubles; ++i)
          k->to->slot_forces()[InternalForces::kSlotDoubles * into.receive[j] + i] =
              k->from->slot_forces()[InternalForces::kSlotDoubles * out_of.send[j] + i];
    };
    return e;
  }
};

Model box_model() { return build_model(samples::make_box_mesh(16, 16, 8, 0.16, 0.16, 0.08), box_material()); }

}  // namespace

TEST(Decomposition, AtomsAndRanksAreFixedAndTheQualityIsRecountedIndependently) {
  const Model m = box_model();
  const std::size_t tets = m.conn.size() / 4;
  const Decomposition one = decompose(m, 1);
  EXPECT_EQ(one.atom_rank.size(), (tets + 127) / 128);
  EXPECT_EQ(one.edge_cut_faces, 0u);
  for (int ranks = 2; ranks <= 4; ++ranks) {
    const Decomposition d = decompose(m, ranks), again = decompose(m, ranks);
    EXPECT_EQ(d.tet_atom, one.tet_atom) << ranks;  // atoms do not depend on the rank count
    EXPECT_EQ(d.atom_rank, again.atom_rank) << ranks;
    std::map<std::array<std::int32_t, 3>, std::vector<std::size_t>> faces;
    std::vector<std::set<std::int32_t>> node_ranks(m.num_nodes);
    std::vector<std::size_t> atom_size(d.atom_rank.size(), 0);
    for (std::size_t e = 0; e < tets; ++e) {
      const std::int32_t r = d.atom_rank[d.tet_atom[e]];
      ++atom_size[d.tet_atom[e]];
      for (int skip = 0; skip < 4; ++skip) {
        std::array<std::int32_t, 3> f{};
        for (int k = 0, i = 0; k < 4; ++k)
          if (k != skip) f[static_cast<std::size_t>(i++)] = m.conn[4 * e + static_cast<std::size_t>(k)];
        std::sort(f.begin(), f.end());
        faces[f].push_back(e);
      }
      for (int k = 0; k < 4; ++k) node_ranks[static_cast<std::size_t>(m.conn[4 * e + static_cast<std::size_t>(k)])].insert(r);
    }
    std::size_t cut = 0;
    for (const auto& [f, on] : faces) cut += on.size() == 2 && d.atom_rank[d.tet_atom[on[0]]] != d.atom_rank[d.tet_atom[on[1]]];
    std::vector<std::size_t> halo(static_cast<std::size_t>(ranks), 0), rank_tets(static_cast<std::size_t>(ranks), 0);
    for (const auto& s : node_ranks)
      if (s.size() > 1)
        for (std::int32_t r : s) ++halo[static_cast<std::size_t>(r)];
    for (std::size_t e = 0; e < tets; ++e) ++rank_tets[static_cast<std::size_t>(d.atom_rank[d.tet_atom[e]])];
    std::printf("%d ranks: %zu atoms, edge cut %zu faces (recounted %zu), imbalance %.2f %%, halo nodes", ranks, d.atom_rank.size(), d.edge_cut_faces,
                cut, 100 * d.load_imbalance);
    for (std::size_t r = 0; r < halo.size(); ++r) std::printf(" %zu (recounted %zu)", d.halo_nodes[r], halo[r]);
    std::printf("\n");
    EXPECT_EQ(d.edge_cut_faces, cut);
    EXPECT_GT(cut, 0u);
    for (std::size_t r = 0; r < halo.size(); ++r) {
      EXPECT_EQ(d.halo_nodes[r], halo[r]);
      EXPECT_EQ(d.rank_tets[r], rank_tets[r]);
      EXPECT_EQ(d.rank_cost[r], static_cast<std::int64_t>(kStandardCost * rank_tets[r]));  // one standard material
    }
    for (std::size_t n : atom_size) EXPECT_LE(n, 128u);
    EXPECT_LE(d.load_imbalance, 0.05);
  }
  EXPECT_THROW(decompose(m, 0), InputError);
  EXPECT_THROW(decompose(m, static_cast<int>(one.atom_rank.size()) + 1), InputError);
}

// A partition given by the user (a cut placed on purpose): METIS's own, written and read back,
// measures the same; a list of another length, a rank out of range and a rank with no atom are
// refused naming the entry.
TEST(Decomposition, AGivenPartitionIsMeasuredAndCheckedEntryByEntry) {
  const Model m = box_model();
  const Decomposition d = decompose(m, 3);
  const testkit::TempDir dir;
  const auto write = [&](const nlohmann::json& j) {
    const auto file = dir.path() / "partition.json";
    std::ofstream(file) << j.dump();
    return file;
  };
  const Decomposition back = read_partition(m, write(decomposition_json(d)));
  std::printf("given partition: edge cut %zu faces (METIS's %zu), imbalance %.2f %% (%.2f %%)\n", back.edge_cut_faces, d.edge_cut_faces,
              100 * back.load_imbalance, 100 * d.load_imbalance);
  EXPECT_EQ(back.atom_rank, d.atom_rank);
  EXPECT_EQ(back.edge_cut_faces, d.edge_cut_faces);
  EXPECT_EQ(back.halo_nodes, d.halo_nodes);
  EXPECT_EQ(back.load_imbalance, d.load_imbalance);
  nlohmann::json j = decomposition_json(d);
  j["atom_rank"].erase(j["atom_rank"].begin());
  testkit::expect_input_error([&] { read_partition(m, write(j)); }, {"atom_rank", "96 ranks", "95 entries"});
  j = decomposition_json(d);
  j["atom_rank"][5] = 3;
  testkit::expect_input_error([&] { read_partition(m, write(j)); }, {"atom_rank[5]", "0 to 2", "3"});
  j = decomposition_json(d);
  for (auto& r : j["atom_rank"]) r = r.get<int>() == 2 ? 1 : r.get<int>();
  testkit::expect_input_error([&] { read_partition(m, write(j)); }, {"none for rank 2"});
}

// Two ranks simulated in one process (what RankStressPass does over MPI, tests/ranks): each
// InternalForces runs only its rank's atoms and keeps only the slots it fills or receives; the
// slots rank 0 receives match those rank 1 sends by position (each side lists them node by node in
// atom order, in its own numbering), and once rank 1's values are copied into them, rank 0's
// forces at every node its atoms touch are the bits of one process, from fewer slots than one
// process holds.
TEST(Decomposition, TwoRanksInOneProcessAddTheSameBitsAsOne) {
  const Model model = build_model(samples::make_box_mesh(8, 8, 4, 0.08, 0.08, 0.04), box_material());
  const Decomposition d = decompose(model, 2);
  std::vector<double> u(3 * model.num_nodes);
  for (std::size_t n = 0; n < model.num_nodes; ++n)
    for (int i = 0; i < 3; ++i) u[3 * n + i] = 0.01 * std::sin(40.0 * model.X[3 * n + (i + 1) % 3] + i);
  InternalForces one(model, 0.0, 1), rank0(model, 0.0, 1), rank1(model, 0.0, 1);
  std::vector<double> f_one(3 * model.num_nodes), f0(3 * model.num_nodes), f1(3 * model.num_nodes);
  one.compute(u.data(), nullptr, f_one.data());
  rank0.own_atoms(d.tet_atom, d.atom_rank, 0);
  rank1.own_atoms(d.tet_atom, d.atom_rank, 1);
  ASSERT_EQ(rank0.halo().size(), 1u);
  ASSERT_EQ(rank1.halo().size(), 1u);
  EXPECT_EQ(rank0.halo()[0].rank, 1);
  EXPECT_EQ(rank0.halo()[0].receive.size(), rank1.halo()[0].send.size());
  EXPECT_EQ(rank1.halo()[0].receive.size(), rank0.halo()[0].send.size());
  rank1.compute(u.data(), nullptr, f1.data());
  HaloCopy copy{&rank0, &rank1};
  rank0.compute(u.data(), nullptr, f0.data(), StressSideTask{}, copy.exchange());
  std::size_t compared = 0, differ = 0;
  for (std::size_t e = 0; e < model.num_elements; ++e)
    if (d.atom_rank[d.tet_atom[e]] == 0)
      for (int k = 0; k < 4; ++k) {
        const auto n = static_cast<std::size_t>(model.conn[4 * e + static_cast<std::size_t>(k)]);
        for (int i = 0; i < 3; ++i) ++compared, differ += std::memcmp(&f0[3 * n + i], &f_one[3 * n + i], sizeof(double)) != 0;
      }
  std::printf("2 ranks in one process: %zu shared slots each way, %zu of %zu force components (with repeats) at rank 0's nodes differ in any bit\n",
              rank0.halo()[0].receive.size(), differ, compared);
  EXPECT_GT(rank0.halo()[0].receive.size(), 0u);
  EXPECT_EQ(differ, 0u);
  // Each rank holds its atoms' slots and corners and the halo's, not the other rank's.
  std::printf("stress-pass bytes: one process %zu, rank 0 %zu, rank 1 %zu\n", one.memory_bytes(), rank0.memory_bytes(), rank1.memory_bytes());
  EXPECT_LT(rank0.memory_bytes(), one.memory_bytes());
  EXPECT_LT(rank1.memory_bytes(), one.memory_bytes());
}

// Each rank keeps its own atoms' geometry and connectivity and the model releases its own
// (InternalForces::hold_own_geometry, Model::release_tet_geometry). Its pass must read the same
// nodes, reference gradients, volumes and per-tet law data as before: hgo with random fibres per
// tet (the law's data travels too), both ranks' forces at their nodes, the sum of their energies
// and each tet's cell record and nodes against one process's bits, computed before the release.
TEST(Decomposition, RanksHoldingTheirOwnGeometryAddTheSameBitsOnceTheModelReleasesIt) {
  Model model = build_model(samples::make_box_mesh(8, 8, 4, 0.08, 0.08, 0.04), testkit::paper_hgo(1e8, "standard"));
  MaterialBlock& block = model.blocks[0];
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  block.element_data.resize(6 * model.num_elements);
  for (std::size_t k = 0; k < block.element_data.size(); k += 3) {
    double* a = &block.element_data[k];
    for (int j = 0; j < 3; ++j) a[j] = noise(rng);
    const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    for (int j = 0; j < 3; ++j) a[j] /= n;
  }
  const Decomposition d = decompose(model, 2);
  std::vector<double> u(3 * model.num_nodes);
  for (std::size_t n = 0; n < model.num_nodes; ++n)
    for (int i = 0; i < 3; ++i) u[3 * n + i] = 0.0005 * std::sin(40.0 * model.X[3 * n + (i + 1) % 3] + i);
  std::vector<double> f_one(3 * model.num_nodes);
  double energy_one = 0;
  const std::size_t width = cell_record_width(model);
  std::vector<double> records_one(width * model.num_elements), records_ranks(records_one.size(), -1.0);
  // Mass scaling's scans (tets below a floor, the smallest scaled step): half the tets below.
  double floor2 = 0;
  std::vector<FloorTet> below_one;
  std::pair<double, std::size_t> smallest_one;
  std::vector<double> factors_one;
  {
    InternalForces one(model, 0.0, 1);
    one.enable_mass_scaling();
    energy_one = one.compute(u.data(), nullptr, f_one.data()).strain_energy;
    std::vector<double> dt2 = one.element_dt2();
    std::nth_element(dt2.begin(), dt2.begin() + static_cast<std::ptrdiff_t>(dt2.size() / 2), dt2.end());
    floor2 = dt2[dt2.size() / 2];
    one.raise_to_floor(floor2, below_one);
    smallest_one = one.smallest_scaled_step(1e-7);
    factors_one = one.mass_factors();  // (model order)
    one.cell_records(u.data(),
                     [&](std::size_t, std::size_t e, const std::int32_t*, const double* r) { std::copy(r, r + width, &records_one[width * e]); });
  }
  InternalForces rank0(model, 0.0, 1), rank1(model, 0.0, 1);
  rank0.own_atoms(d.tet_atom, d.atom_rank, 0);
  rank1.own_atoms(d.tet_atom, d.atom_rank, 1);
  std::vector<TetRange> tets0, tets1;
  for (std::size_t e = 0; e < model.num_elements; ++e) {
    std::vector<TetRange>& mine = d.atom_rank[d.tet_atom[e]] == 0 ? tets0 : tets1;
    if (mine.empty() || mine.back().end != e) mine.push_back({e, e});
    ++mine.back().end;
  }
  rank0.hold_own_geometry(tets0), rank1.hold_own_geometry(tets1);
  rank0.enable_mass_scaling(), rank1.enable_mass_scaling();  // (their factors and steps: the held tets')
  const std::vector<std::int32_t> conn = model.conn;
  const std::size_t whole = model.memory_bytes();
  model.release_tet_geometry();
  const std::size_t released = whole - model.memory_bytes(), per_tet = 4 * sizeof(std::int32_t) + (9 + 1 + 6) * sizeof(double);
  std::printf("released %zu bytes of the model's %zu (%zu tets: nodes, gradients, volume and 6 fibre components, %zu bytes each)\n", released, whole,
              model.num_elements, per_tet);
  EXPECT_EQ(released, per_tet * model.num_elements);
  EXPECT_THROW(InternalForces(model, 0.0, 1), std::logic_error);
  EXPECT_THROW(static_cast<void>(model.blocks[0].data()), std::logic_error);
  // Each rank's pass with the other's halo slots copied in.
  std::vector<double> f0(3 * model.num_nodes), f1(3 * model.num_nodes);
  rank1.compute(u.data(), nullptr, f1.data());
  HaloCopy to0{&rank0, &rank1}, to1{&rank1, &rank0};
  rank0.compute(u.data(), nullptr, f0.data(), StressSideTask{}, to0.exchange());
  rank1.compute(u.data(), nullptr, f1.data(), StressSideTask{}, to1.exchange());
  std::size_t compared = 0, differ = 0;
  for (std::size_t e = 0; e < model.num_elements; ++e) {
    const std::vector<double>& f = d.atom_rank[d.tet_atom[e]] == 0 ? f0 : f1;
    for (int k = 0; k < 4; ++k) {
      const auto n = static_cast<std::size_t>(conn[4 * e + static_cast<std::size_t>(k)]);
      for (int i = 0; i < 3; ++i) ++compared, differ += std::memcmp(&f[3 * n + i], &f_one[3 * n + i], sizeof(double)) != 0;
    }
  }
  PassSums both = rank0.pass_sums();
  const auto words = rank1.pass_sums().energy.words();
  both.energy.add_words(words.data());
  const double energy_ranks = both.energy.value();
  std::printf("held geometry, 2 ranks: %zu of %zu force components (with repeats) differ in any bit; strain energy %.17g J, one process %.17g J\n",
              differ, compared, energy_ranks, energy_one);
  EXPECT_EQ(differ, 0u);
  EXPECT_EQ(std::memcmp(&energy_ranks, &energy_one, sizeof(double)), 0);
  // The states' cell records (stress, von Mises, J, hgo's fibre stretches), each tet's from the
  // rank that holds it, against one process's before the release.
  std::size_t given = 0, wrong_nodes = 0;
  for (const InternalForces* rank : {&rank0, &rank1})
    rank->cell_records(u.data(), [&](std::size_t, std::size_t e, const std::int32_t* nodes, const double* r) {
      ++given;
      wrong_nodes += !std::equal(nodes, nodes + 4, &conn[4 * e]);
      std::copy(r, r + width, &records_ranks[width * e]);
    });
  const bool same = std::memcmp(records_ranks.data(), records_one.data(), records_one.size() * sizeof(double)) == 0;
  std::printf(
      "cell records: %zu of %zu tets given by the two ranks (%zu doubles each), the same bits as one process's: %s; %zu with "
      "other nodes than the model's\n",
      given, model.num_elements, width, same ? "yes" : "no", wrong_nodes);
  EXPECT_EQ(given, model.num_elements);
  EXPECT_TRUE(same);
  EXPECT_EQ(wrong_nodes, 0u);
  // A message's tet: each rank gives the nodes of its own tets and none of the other's.
  std::size_t found = 0;
  for (std::size_t e = 0; e < model.num_elements; ++e) {
    const InternalForces& owner = d.atom_rank[d.tet_atom[e]] == 0 ? rank0 : rank1;
    const InternalForces& other = &owner == &rank0 ? rank1 : rank0;
    found +=
        owner.nodes_of_tet(e) &&
        std::equal(conn.begin() + static_cast<std::ptrdiff_t>(4 * e), conn.begin() + static_cast<std::ptrdiff_t>(4 * e + 4), owner.nodes_of_tet(e)) &&
        !other.nodes_of_tet(e);
  }
  EXPECT_EQ(found, model.num_elements);
  // Mass scaling's scans from the held geometry: the two ranks' tets below the floor, raised,
  // merged in tet order, the smaller of their smallest steps and every tet's factor from the rank
  // that holds it, against one process's.
  std::vector<FloorTet> below;
  rank0.raise_to_floor(floor2, below), rank1.raise_to_floor(floor2, below);
  std::sort(below.begin(), below.end(), [](const FloorTet& a, const FloorTet& b) { return a.tet < b.tet; });
  std::size_t floor_differ = below.size() != below_one.size();
  for (std::size_t k = 0; k < std::min(below.size(), below_one.size()); ++k)
    floor_differ += below[k].tet != below_one[k].tet || std::memcmp(&below[k].rho_v, &below_one[k].rho_v, sizeof(double)) != 0 ||
                    std::memcmp(&below[k].factor_before, &below_one[k].factor_before, sizeof(double)) != 0 ||
                    std::memcmp(&below[k].factor_after, &below_one[k].factor_after, sizeof(double)) != 0 || below[k].nodes != below_one[k].nodes;
  const auto s0 = rank0.smallest_scaled_step(1e-7), s1 = rank1.smallest_scaled_step(1e-7);
  const auto smallest = s1.first < s0.first || (s1.first == s0.first && s1.second < s0.second) ? s1 : s0;
  std::printf(
      "mass scaling: %zu of %zu tets below the floor from the two ranks, %zu differ from one process's %zu; smallest scaled step "
      "%.17g s at tet %zu (one process %.17g s at tet %zu)\n",
      below.size(), model.num_elements, floor_differ, below_one.size(), smallest.first, smallest.second, smallest_one.first, smallest_one.second);
  EXPECT_GT(below_one.size(), model.num_elements / 4);
  EXPECT_EQ(floor_differ, 0u);
  EXPECT_EQ(std::memcmp(&smallest.first, &smallest_one.first, sizeof(double)), 0);
  EXPECT_EQ(smallest.second, smallest_one.second);
  // (each rank's factors: its tets', ascending)
  std::size_t factors_differ = 0, factors_held = 0;
  for (const auto& [rank, tets] : {std::pair{&rank0, &tets0}, std::pair{&rank1, &tets1}}) {
    std::size_t k = 0;
    for (const TetRange& r : *tets)
      for (std::size_t e = r.begin; e < r.end; ++e, ++k)
        factors_differ += std::memcmp(&rank->mass_factors()[k], &factors_one[e], sizeof(double)) != 0;
    factors_held += rank->mass_factors().size();
    EXPECT_EQ(k, rank->mass_factors().size());
  }
  EXPECT_EQ(factors_held, model.num_elements);
  std::printf("mass factors after the raise: %zu of %zu tets differ from one process's\n", factors_differ, model.num_elements);
  EXPECT_EQ(factors_differ, 0u);
}
