#pragma once
// The stress pass: one loop over all tets computing the internal (and viscous) nodal forces,
// the strain energy, the smallest Jacobian and the element stable step, in the same pass
// (Laghos' qdata.dt_est idea). Race-free and deterministic assembly: the partitions are the
// model's atoms (kAtomTets consecutive tets of a block, model.hpp), each scattering into its own
// compact force array, one slot per node its tets touch; every node's sum is then taken over its
// slots in atom order, so the forces, energies and steps are bit-identical for any number of
// threads, and a rank that owns whole atoms can add the same terms in the same order.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "tactus/solver/exact_sum.hpp"
#include "tactus/solver/model.hpp"

namespace tactus::solver {

// Gradient of a nodal vector field over a one-point tet: sum_a w_a (x) grad N_a, written with the
// differences to node 0 (grad N_0 = -sum of the others). conn: the tet's 4 nodes; grad: its 9
// stored reference gradients. Gives F - I from displacements and Fdot from velocities.
[[gnu::always_inline]] inline Mat3 nodal_gradient(const double* __restrict field, const std::int32_t* conn, const double* __restrict grad) {
  const double* w0 = field + 3 * static_cast<std::size_t>(conn[0]);
  const double* w1 = field + 3 * static_cast<std::size_t>(conn[1]);
  const double* w2 = field + 3 * static_cast<std::size_t>(conn[2]);
  const double* w3 = field + 3 * static_cast<std::size_t>(conn[3]);
  Mat3 G;
  for (int i = 0; i < 3; ++i) {
    const double d1 = w1[i] - w0[i], d2 = w2[i] - w0[i], d3 = w3[i] - w0[i];
    for (int j = 0; j < 3; ++j) G(i, j) = d1 * grad[j] + d2 * grad[3 + j] + d3 * grad[6 + j];
  }
  return G;
}

struct StressPassResult {
  double strain_energy = 0;  // sum_e V_e W(F_e)
  double viscous_power = 0;  // sum_e V_e P_visc : Fdot (>= 0), Rayleigh beta part
  // The stable step (no safety factor): the larger of two upper bounds on omega_max, each enough
  // alone: the element estimate min_e dt_e (limiting_element) and, when on, the nodal bound
  // (limiting_node; InternalForces::set_nodal_step_bound).
  double critical_step = 0;
  double element_critical_step = 0, nodal_critical_step = 0;  // nodal: 0 when off
  bool limited_by_node = false;
  std::size_t limiting_node = 0;
  std::size_t limiting_element = 0;
  double min_jacobian = 0;
  std::size_t min_jacobian_element = 0;
};

// Average nodal pressure tets (material.hpp, kernels/element_loop.hpp), for the blocks whose
// material runs as ANP: the nodal reference volumes V_a = sum_e V_e / 4 over the block's tets
// (0 at the other nodes), one entry per node; adding the current volume v_e / 4 of `count` tets
// (their nodes from `conn`, 4 per tet) at u to the nodes' current volumes; and the nodal pressures
// U'(J_a) at u (serial: for the outputs).
std::vector<double> anp_reference_node_volumes(const Model& model, const MaterialBlock& block);
// node_volume[n] receives node n's share, or node_volume[slot[4 e + k]] for corner k of the e-th
// tet when the slots of their corners are given (an atom's compact array; InternalForces).
void add_current_node_volumes(const Model& model, const std::int32_t* conn, std::size_t count, const double* u, double* node_volume,
                              const std::uint16_t* slot = nullptr);
// Per tet of the block (from its first): the constant factor of its ANP volumetric rows in the
// nodal step bound (InternalForces; design.md, "Stable step").
std::vector<double> anp_step_bound_factors(const Model& model, const MaterialBlock& block, const std::vector<double>& node_reference_volume);
std::vector<double> anp_nodal_pressure(const Model& model, const MaterialBlock& block, const double* u);

// One pass of the pressure smoothing of an ANP block, node -> tet -> node and V-weighted, as a
// node-to-node operator: (S x)_a = sum_b W_ab x_b, W_ab = sum_{e of the block containing a and b}
// (V_e / 16) / V_a. The diagonal is 1/4 at every node of the block (V_a = sum_e V_e / 4), so the
// rows hold only the neighbours b != a, ascending (each sum in the same order on any thread);
// a node without a tet of the block gets 0.
struct NodeAveraging {
  std::vector<std::size_t> row;  // num_nodes + 1
  std::vector<std::int32_t> column;
  std::vector<double> weight;
  NodeAveraging() = default;
  NodeAveraging(const Model& model, const MaterialBlock& block, const std::vector<double>& node_reference_volume);
  // y[a] = (S x)_a for the nodes a in [lo, hi) (y must not alias x).
  void apply(const double* x, double* y, std::size_t lo, std::size_t hi) const {
    for (std::size_t a = lo; a < hi; ++a) {
      if (row[a] == row[a + 1]) {
        y[a] = 0;
        continue;
      }
      double sum = 0.25 * x[a];
      for (std::size_t k = row[a]; k < row[a + 1]; ++k) sum += weight[k] * x[column[k]];
      y[a] = sum;
    }
  }
  std::size_t memory_bytes() const {
    return row.capacity() * sizeof(std::size_t) + column.capacity() * sizeof(std::int32_t) + weight.capacity() * sizeof(double);
  }
};

// The rest operator's rows of an ANP block's volumetric part in the nodal step bound (design.md,
// "Stable step"): per node b, k (|G0|^T V S^2s |G0| p)_b / p_b with |G0|_ab the norm of the block
// row a, column b of the reference volume-rate map (the sum over the tets at a and b of V0 grad_X N_b,
// over 4 V_a), S the block's averaging (nullptr: no smoothing), s its passes and p = V^(-1/2).
std::vector<double> anp_rest_rows(const Model& model, const MaterialBlock& block, const std::vector<double>& node_reference_volume,
                                  const NodeAveraging* averaging);

// The Cauchy stress of every tet (model numbering) at u, one process over the whole model, apart
// from the stress pass (the tests' reference for the reported stress, InternalForces::cell_records):
// an ANP tet's volumetric part is the average of its nodes' pressures, summed tet by tet.
std::vector<Mat3> element_cauchy_stress(const Model& model, const double* u);

// One tet's record of the state files' cell fields: its Cauchy stress in Voigt order (xx yy zz xy
// yz xz), von Mises, J = det F, then its block's law result values (hgo: fibre_stretch) in the
// order of its law's result_fields; cell_record_width: the longest over the model's blocks. The
// stress pass fills them (InternalForces::cell_records) from the geometry it reads, and the
// writer takes them from it (on ranks gathered to rank 0), so the file reports the stress the
// forces came from.
inline constexpr std::size_t kCellRecordFixed = 8;
std::size_t cell_record_width(const Model& model);
void fill_cell_record(const MaterialBlock& block, const Mat3& F, const Mat3& sigma, const double* law_data, double* record);
// A tet's record with its block, its model index and its four nodes (model numbering: the writer
// takes the cells from them, so no process needs the whole connectivity to write a state).
using CellSink = std::function<void(std::size_t block, std::size_t tet, const std::int32_t* nodes, const double* record)>;

// Mass scaling: a tet whose step with its mass factor was below the floor, as the process that
// runs it found and raised it: its model index, rho V, its mass factor before and after (its step
// then meets the floor) and its nodes.
struct FloorTet {
  std::size_t tet = 0;
  double rho_v = 0, factor_before = 0, factor_after = 0;
  std::array<std::int32_t, 4> nodes{};
};

// A run of consecutive tets [begin, end) (model numbering).
struct TetRange {
  std::size_t begin = 0, end = 0;
};

// What a run of the element loop (kernels/element_loop.hpp) accumulates besides the forces.
struct StressAccumulator {
  double energy = 0, viscous_power = 0;
  double dt2 = std::numeric_limits<double>::infinity();  // squared element step (no beta)
  double dt = std::numeric_limits<double>::infinity();   // element step with beta
  std::size_t dt_element = 0;
  double min_J = std::numeric_limits<double>::infinity();
  std::size_t min_J_element = 0;
};

// The pass's sums over atoms (strain energy, ANP volumetric energy included, and viscous power),
// exact so that they do not depend on which process or thread adds which atom.
struct PassSums {
  ExactSum energy, viscous_power;
};

struct StressSideTask {
  void (*run)(void* context) = nullptr;
  void* context = nullptr;
};

// On ranks (solver/ranks.hpp): called by the master thread once the atoms whose slots other ranks
// need are done (start: send and receive them) and before the nodal sums (finish: wait, unpack).
// With ANP blocks, in their J pass: the halo slots' nodal volumes once the rank's ANP atoms have
// added theirs (volumes), and a nodal array's values at the rank's ghost nodes from their owners
// after each node pass (nodes: InternalForces::anp_ghosts).
struct StressExchange {
  void (*start)(void* context) = nullptr;
  void (*finish)(void* context) = nullptr;
  void (*volumes)(void* context) = nullptr;
  void (*nodes)(void* context, double* values) = nullptr;
  void* context = nullptr;
};

// The nodes of the ANP J pass one rank sends another after each node pass (those it owns and the
// other reads but does not compute) and those it receives from it (ascending, both sides alike).
struct NodeGhosts {
  int rank = 0;
  std::vector<std::uint32_t> send, receive;
};

// The slots of the nodes one rank shares with another: those this rank's atoms fill and sends, and
// those the other's fill and it receives (InternalForces::kSlotDoubles each, in the listed order;
// each in its own rank's slot numbering, node by node and each node's in atom order on both sides).
// With the nodal step bound and ANP blocks, also the ANP tiles (their c^2, kernels/element_loop.hpp)
// that hold a node the two share: this rank's atoms' (sent) and the other's (received), ascending.
struct HaloSlots {
  int rank = 0;
  std::vector<std::uint32_t> send, receive;
  std::vector<std::uint32_t> send_tiles, receive_tiles;
};

// The nodal step bound's largest rows over some node chunks (InternalForces): the plain form's
// omega^2 and node, and per splitting weight eta of the ANP form its own. Ranks take each one's
// largest over all ranks (MAXLOC), then the step as one process does (InternalForces::nodal_step).
struct NodalBoundRows {
  static constexpr int kEtas = 13;
  double plain = 0;
  std::size_t plain_node = 0;
  bool has_eta = false;
  double eta[kEtas] = {};
  std::size_t eta_node[kEtas] = {};
};

class InternalForces {
 public:
  static constexpr std::size_t kNodeChunk = 512;
  static constexpr std::size_t kSlotDoubles = 4;  // per slot of slot_forces(): the force and its nodal bound row sum
  // beta: Rayleigh stiffness-proportional damping (s); threads <= 0: all cores, at most one per ~4000 tets.
  InternalForces(const Model& model, double beta, int threads);
  // f_out (3 per node) = -(f_int + f_visc) at displacement u and velocity v (v used if beta > 0).
  // side: work that may run on one thread while the others take the stress partitions (the next
  // step's contact detection, which reads the same u); that thread then joins them.
  StressPassResult compute(const double* u, const double* v, double* f_out, StressSideTask side = StressSideTask{},
                           StressExchange exchange = StressExchange{});
  // Ranks (once): from now on only the atoms of `rank` run (tet_atom and atom_rank: a Decomposition
  // of this model with kAtomTets atoms), and only their slots and those of the halo they receive
  // are kept (halo() lists them in this rank's numbering: a pair's lists match by position);
  // f_out is then right at the nodes they touch once the halo()
  // slots are exchanged (slot_forces()), and the result holds only this rank's atoms (the whole
  // one: pass_result of every rank's pass_sums() added; the other ranks' atoms keep empty results
  // here, so the result's minima are this rank's). The ANP blocks' J pass runs
  // over the rank's own nodes, with its ghost nodes' values exchanged after each node pass
  // (anp_ghosts()).
  void own_atoms(const std::vector<std::uint32_t>& tet_atom, const std::vector<std::int32_t>& atom_rank, int rank);
  // Ranks, after own_atoms: copies the connectivity, reference gradients, volumes and per-tet law
  // data (fibres) of `tets` (this rank's share of the decomposition, ascending: its atoms' tets and
  // those without a stress pass, rigid or joint gaps, whose results it reports) into arrays of its
  // own and reads them from there, so the model's may be released (Model::release_tet_geometry;
  // 96 bytes per tet and the law's data, of which this rank keeps its share).
  void hold_own_geometry(const std::vector<TetRange>& tets);
  // After a pass at u: the cell record (cell_record_width(model) doubles) of every tet this
  // process holds (one process: every tet; after hold_own_geometry: those it holds), in model
  // order, each handed to sink. An ANP tet's volumetric part is the mean of its nodes' pressures
  // of that pass (the pressures its forces came from).
  void cell_records(const double* u, const CellSink& sink) const;
  // Tet e's four nodes where this process reads them (after hold_own_geometry: its own tets',
  // else the model's), or nullptr.
  const std::int32_t* nodes_of_tet(std::size_t e) const;
  const std::vector<HaloSlots>& halo() const { return halo_; }
  double* slot_forces() { return partition_forces_.data(); }
  double* slot_volumes() { return partition_volumes_.data(); }  // the ANP atoms' nodal volumes, 1 per slot
  const std::vector<NodeGhosts>& anp_ghosts() const { return anp_ghosts_; }
  double* anp_tile_values() { return anp_tiles_.data(); }
  // The nodal bound of the last pass (nullptr-mass: off): this process's chunks' largest rows, and
  // the step such rows give (into r, beside the element estimate).
  bool nodal_bound_on() const { return nodal_mass_ != nullptr; }
  NodalBoundRows nodal_bound_rows() const;
  void nodal_step(const NodalBoundRows& rows, StressPassResult& r) const;
  // Per atom of the stress pass (atom order): its rank (after own_atoms).
  const std::vector<int>& atom_ranks() const { return partition_rank_; }
  // Per node (after own_atoms): the rank of the first atom whose stress-pass tets hold it, the one
  // rank certain to have its every slot after the exchange; -1 for a node no such tet holds (its
  // force is 0 on every rank).
  const std::vector<std::int32_t>& node_ranks() const { return node_rank_; }
  // Per node (after own_atoms): 1 where a stress-pass tet of this rank's atoms holds it, the nodes
  // whose forces the exchange makes whole here.
  const std::vector<char>& touched() const { return touched_; }
  // ANP blocks on ranks: per node chunk the rank whose pass has its volumetric energy right (each
  // rank runs the J pass over its own and ghost nodes only).
  const std::vector<std::int32_t>& chunk_ranks() const { return chunk_rank_; }
  // The last pass's sums over this process's atoms and ANP node chunks (every one in one process;
  // on ranks those it owns and reports), exact: the whole model's are every rank's added.
  const PassSums& pass_sums() const { return sums_; }
  // The pass's result from the sums over every atom and chunk and from this process's atoms'
  // minima (ties of the smallest step or Jacobian to the first atom); the nodal bound not included.
  StressPassResult pass_result(const PassSums& sums) const;
  int threads() const { return threads_; }
  // The threads of the next passes (the sums do not depend on them: ThreadTuner changes them as a run goes).
  void set_threads(int threads) { threads_ = threads; }
  std::size_t memory_bytes() const;
  // Mass scaling: from now on every pass stores each tet's unscaled squared stable step (no beta)
  // and computes the step with its mass factor (1 + added / (rho V)), both per tet this process
  // holds (one process: model order; on ranks, enabled after hold_own_geometry: its held tets', in
  // their order).
  void enable_mass_scaling();
  const std::vector<double>& element_dt2() const { return element_dt2_; }
  // Over the tets with a stress pass this process runs (one process: every one; ranks: its atoms'),
  // in tet order: raises the factor of each whose step is below the floor (floor2: its square) to
  // floor2 / dt2 and appends it to `out`; and the smallest step with the factors as they are, as
  // the kernel computes it (beta: stiffness damping), with its tet, the first at a tie (infinity
  // and no tet when it runs none).
  void raise_to_floor(double floor2, std::vector<FloorTet>& out);
  std::pair<double, std::size_t> smallest_scaled_step(double beta) const;
  // The mass factors of the tets this process holds, in their order (one process: model order;
  // after hold_own_geometry: its held tets', ascending); set_mass_factors takes those of its tets
  // from every tet's (model order: a checkpoint holds them whole).
  const std::vector<double>& mass_factors() const { return mass_factor_; }
  void set_mass_factors(const std::vector<double>& whole);
  // The nodal step bound (on by default, with the model's lumped masses): a second upper bound on
  // omega_max from the nodes' whole masses, where the element estimate sees only each tet's share
  // of them (design.md, "The stable step"). nodal_mass: per node, the masses the run integrates
  // with (which mass scaling raises); nullptr turns it off. Nodes with all three dofs prescribed
  // do not move and are left out.
  void set_nodal_step_bound(const double* nodal_mass);
  // The stress pass takes lanes::kLanes tets at a time (default) or one at a time: the same
  // formulas (kernels/lanes.hpp), kept selectable as the reference the vector kernels are tested
  // and benched against. (The ANP J pass is scalar either way: it is all gathers and scatters.)
  void set_vectorised(bool on) { vectorised_ = on; }
  static int lanes();  // tets per vector group

 private:
  const Model& model_;
  double beta_;
  int threads_;
  bool vectorised_ = true;
  // An atom: a contiguous run of one block's tets and the slots [slot_begin, slot_end), one per
  // node its tets touch (ascending node order). Its forces go to partition_forces_, 4 per slot from
  // kForceStride slot_begin: the force and its nodal step bound's row sum, side by side so the two
  // scatters share a cache line (kernels/element_loop.hpp); its current nodal volumes (ANP blocks)
  // to partition_volumes_ from slot_begin. A slot array rather than the atom's node range: 128
  // Morton-ordered tets touch ~60 nodes spread over thousands of indices (a range cost 8x the
  // memory and 3.6x the time of the pass).
  struct Partition {
    std::size_t block, begin, end, slot_begin, slot_end;
    std::size_t tile_offset = 0;   // ANP blocks: its tiles' first in anp_tiles_
    std::size_t corner_begin = 0;  // its first tet's corner in tet_slot_
    // After hold_own_geometry: its first tet in held_conn_ / held_grad_ / held_volume_, and its
    // first tet's law data in held_data_ (blocks with per-tet data).
    std::size_t held_tet = 0, held_data = 0;
  };
  // The geometry this rank's atoms read (hold_own_geometry; empty: the model's): per held run of
  // one block's tets, where its first tet's are.
  struct HeldRun {
    std::size_t block, begin, end, tet, data;
  };
  bool holds_geometry_ = false;
  // The per-tet arrays this process reads: its own once it holds them (hold_own_geometry), else the
  // model's; a tet's index in them, and in mass_factor_ and element_dt2_, is held_index (an atom's
  // first: its held_tet there, its model index here).
  std::size_t held_index(std::size_t held_tet, std::size_t model_tet) const { return holds_geometry_ ? held_tet : model_tet; }
  const std::int32_t* tet_conn() const { return holds_geometry_ ? held_conn_.data() : model_.conn.data(); }
  const double* tet_grad() const { return holds_geometry_ ? held_grad_.data() : model_.grad.data(); }
  const double* tet_volume() const { return holds_geometry_ ? held_volume_.data() : model_.volume.data(); }
  // f(block, begin, end, at, data) over the runs of one block's tets this process reads, ascending
  // (one process: the blocks; after hold_own_geometry: its held runs): `at` their first tet's index
  // in the arrays above, `data` its law data.
  template <class F>
  void each_run(F f) const;
  std::vector<HeldRun> held_runs_;
  std::vector<std::int32_t> held_conn_;
  std::vector<double> held_grad_, held_volume_, held_data_;
  std::vector<Partition> partitions_;
  std::vector<double> partition_forces_, partition_volumes_;
  // Per corner of the atoms' tets (4 per tet, from each atom's corner_begin): its node's slot within
  // its atom. Per node: its slots, ascending (= atom order), from node_slot_first_[n]. On ranks
  // (keep_rank_slots) only this rank's atoms' corners, and the slots its atoms fill or receive.
  std::vector<std::uint16_t> tet_slot_;
  std::vector<std::size_t> node_slot_first_;
  std::vector<std::uint32_t> node_slots_;
  // Per block: its atoms' slots [first, last) (a node's slots of one block, for the ANP volumes).
  std::vector<std::size_t> block_slot_begin_, block_slot_end_;
  // The ANP blocks' second form of the nodal bound: per tile of kAnpTile tets of an ANP partition
  // (from its tile_offset) the largest c^2 >= |cof F - I|_2^2 (kernels/element_loop.hpp, anp_tiles), per
  // node the tiles holding its ANP tets (anp_node_tiles_ from anp_node_tile_first_[n]), the
  // volumetric rows at the reference state (anp_reference_rows_) and the rest operator's rows
  // (anp_rest_rows_), each summed over the ANP blocks, and per node chunk and splitting weight eta
  // (kEtas of them) the largest row / mass and its node.
  static constexpr int kEtas = NodalBoundRows::kEtas;
  std::vector<double> anp_tiles_, anp_reference_rows_, anp_rest_rows_, chunk_eta_bound_;
  std::vector<std::size_t> anp_node_tile_first_;
  std::vector<std::uint32_t> anp_node_tiles_;
  std::vector<std::size_t> chunk_eta_node_;
  // Nodal step bound: the masses (nullptr: off), the free nodes, the summed row sums, and per node
  // chunk the largest row sum / mass and its node.
  const double* nodal_mass_ = nullptr;
  std::vector<unsigned char> node_moves_;
  std::vector<double> nodal_bound_, chunk_bound_;
  std::vector<std::size_t> chunk_bound_node_;
  std::vector<StressAccumulator> partition_acc_;
  // Nodes in chunks of kNodeChunk (the unit of the nodal passes and their reductions).
  std::size_t num_chunks_ = 0;
  // ANP blocks: their nodal reference volumes and, per step, the nodal pressures (which first
  // hold the current nodal volumes); per node chunk, that chunk's part of the volumetric energy.
  // bound_factor: per tet of the block, the constant factor of its volumetric rows in the nodal
  // step bound (anp_step_bound_factors).
  struct AnpBlock {
    std::size_t block;
    std::vector<double> reference_volume, pressure;
    NodeAveraging averaging;       // with pressure smoothing only
    std::vector<double> smoothed;  // the other buffer of the smoothing passes (num_nodes; with smoothing only)
    std::vector<double> bound_factor;
  };
  std::vector<AnpBlock> anp_;
  std::vector<const double*> block_pressure_;  // per block: its AnpBlock's pressure, or nullptr
  // Per node: 1 when a tet of a rigid block holds it. An ANP tet whose four nodes all are is placed
  // by the rigid pieces (tissue in a joint's gap between two bones), so its volume floor is off.
  std::vector<char> rigid_node_;
  std::vector<double> chunk_anp_energy_;
  // The ANP J pass's units (anp_pass): the ANP atoms whose tets' volumes this process adds, the
  // node runs whose values it computes (runs of consecutive nodes within a node chunk), and those
  // where it turns volume ratios into pressures, each with its part of the volumetric energy: one
  // process, every atom and every chunk whole; on ranks (anp_ghosts_of_rank) its own atoms, the
  // nodes its atoms touch (and those no stress-pass tet holds), and those plus its ghost nodes,
  // with each chunk it reports whole. Per chunk the rank that reports its ANP energy (on ranks).
  struct NodeRun {
    std::size_t lo, hi, chunk;
    bool reported;  // the chunk's energy is this run's (the run is the whole chunk)
  };
  std::vector<std::size_t> anp_volume_atoms_;
  std::vector<NodeRun> anp_runs_, anp_convert_runs_;
  std::vector<double> convert_energy_;  // per convert run, its energy of the last pass
  std::vector<std::int32_t> chunk_rank_;
  int own_rank_ = -1;          // on ranks, this process's (own_atoms); -1: one process, every atom its own
  std::vector<char> touched_;  // on ranks, per node: a tet of this process's atoms holds it (empty: one process)
  PassSums sums_;
  std::vector<NodeGhosts> anp_ghosts_;
  void set_anp_runs(const std::vector<char>& computed, const std::vector<char>& read, int rank);
  void keep_rank_slots(int rank, const std::vector<std::uint32_t>& slot_partition);
  void anp_ghosts_of_rank(int rank, const std::vector<char>& touched, const std::vector<std::uint32_t>& slot_partition);
  std::vector<double> mass_factor_, element_dt2_;  // empty unless mass scaling is on; per held tet
  void anp_pass(const double* u, const StressExchange& exchange);
  std::size_t build_atoms();  // partitions_, their slots and arrays; returns the ANP tiles
  void stress_partition(std::size_t p, const double* u, const double* v, bool viscous);
  // The atoms this process runs: those whose slots go to other ranks, then the rest (one process:
  // all of them, in order); per atom its rank; per other rank the shared slots.
  std::vector<std::size_t> boundary_atoms_, interior_atoms_;
  std::vector<int> partition_rank_;
  std::vector<std::int32_t> node_rank_;
  std::vector<std::size_t> sum_chunks_;  // the node chunks the pass sums (all; on ranks those this rank's atoms touch)
  std::vector<HaloSlots> halo_;
  // The nodal step bound's reduction (kernels/step_bound.cpp): one node chunk's largest rows, then
  // the step they give into r.
  void nodal_bound_of_chunk(std::size_t chunk);
  void nodal_critical_step(StressPassResult& r) const;
  // Nodes [lo, hi) of `out` (kWidth values per node) = each node's slots in [slot_lo, slot_hi) of
  // `arrays` (kStride values per slot: the first kWidth to `out`, and value kWidth to `extra` when
  // given), summed in atom order. only: on ranks, the nodes this process's atoms touch (the
  // others' sums are 0 here: written, not summed).
  template <std::size_t kStride, std::size_t kWidth>
  void sum_nodes(std::size_t lo, std::size_t hi, const std::vector<double>& arrays, std::size_t slot_lo, std::size_t slot_hi, double* out,
                 double* extra = nullptr, const char* only = nullptr) const;
};

}  // namespace tactus::solver
