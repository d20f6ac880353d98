#pragma once
// ExactSum: the exact sum of doubles, rounded once (a fixed-point "superaccumulator": Kulisch's
// long accumulator, here in 32-bit digits held in 64-bit limbs so that carries can wait). Its
// result is a function of the set of values added, not of their order or grouping, so a sum over
// a model's atoms gives the same bits whether one thread, several threads or several MPI ranks
// add them, each rank adding its own and the ranks' accumulators then added limb by limb.
// The stress pass sums its atoms' strain energy and viscous power with it (docs/design.md,
// "The stress pass over MPI ranks": each rank sends its two accumulators, a fixed 1,136 bytes,
// rather than every atom's record).
#include <array>
#include <cstddef>
#include <cstdint>

namespace tactus::solver {

class ExactSum {
 public:
  // Every finite double is m 2^e with m an integer of at most 53 bits and -1074 <= e <= 971; it is
  // kept at bit e + kBias of a fixed-point number (kBias > 1074: the lowest bit is at index 32 or
  // more), whose highest bit is then 2,129: 67 digits of 32 bits, and one more limb for the
  // carries of 2^31 additions of the largest doubles (the top limb keeps its 64 bits).
  static constexpr int kDigitBits = 32;
  static constexpr int kBias = 1074 + kDigitBits;
  static constexpr std::size_t kLimbs = 68;
  // The limbs and three counts of non-finite values (NaN, +inf, -inf): what ranks exchange.
  static constexpr std::size_t kWords = kLimbs + 3;

  void add(double x);
  // The sum rounded to the nearest double (ties to even; NaN if a NaN or both infinities were
  // added, an infinity if one was, or if the exact sum is beyond the doubles' range).
  double value() const;
  void clear();
  // The words (normalised: the same value gives the same words) for a message, and another
  // accumulator's words added (limb by limb: exact, in any order).
  std::array<std::int64_t, kWords> words() const;
  void add_words(const std::int64_t* words);

 private:
  void normalise();
  std::array<std::int64_t, kLimbs> limb_{};
  std::int64_t nan_ = 0, pos_inf_ = 0, neg_inf_ = 0;
  std::uint32_t pending_ = 0;  // additions since the last normalisation (each moves a limb by < 2^32)
};

}  // namespace tactus::solver
