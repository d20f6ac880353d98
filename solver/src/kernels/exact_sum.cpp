// The exact sum (exact_sum.hpp): a double's integer significand is added, in three 32-bit
// digits, at its exponent's place; carries wait in the limbs' upper 32 bits until a
// normalisation, and the value is rounded once from the top three digits with a sticky bit.
#include "tactus/solver/exact_sum.hpp"

#include <cmath>
#include <cstring>
#include <limits>

namespace tactus::solver {

namespace {
__extension__ typedef unsigned __int128 Wide;  // GCC's and Clang's 128-bit integer
constexpr std::int64_t kDigitMask = (std::int64_t{1} << ExactSum::kDigitBits) - 1;
// Additions a limb takes (each < 2^32 in magnitude) with room left in 63 bits.
constexpr std::uint32_t kAdditionsBeforeCarry = 1u << 30;
}  // namespace

void ExactSum::add(double x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const auto biased = static_cast<int>((bits >> 52) & 0x7ff);
  std::uint64_t significand = bits & ((std::uint64_t{1} << 52) - 1);
  const bool negative = bits >> 63;
  if (biased == 0x7ff) {  // a NaN or an infinity
    (significand != 0 ? nan_ : negative ? neg_inf_ : pos_inf_) += 1;
    return;
  }
  if (biased == 0 && significand == 0) return;  // +-0
  if (biased != 0) significand |= std::uint64_t{1} << 52;
  // x = significand 2^(max(biased, 1) - 1075): its lowest bit sits at that exponent + kBias >= 32.
  const int place = (biased == 0 ? 1 : biased) - 1075 + kBias;
  const auto shifted = static_cast<Wide>(significand) << (place % kDigitBits);
  const auto limb = static_cast<std::size_t>(place / kDigitBits);
  for (std::size_t d = 0; d < 3; ++d) {
    const auto digit = static_cast<std::int64_t>((shifted >> (kDigitBits * d)) & static_cast<Wide>(kDigitMask));
    limb_[limb + d] += negative ? -digit : digit;
  }
  if (++pending_ >= kAdditionsBeforeCarry) normalise();
}

void ExactSum::add_words(const std::int64_t* words) {
  for (std::size_t i = 0; i < kLimbs; ++i) limb_[i] += words[i];
  nan_ += words[kLimbs], pos_inf_ += words[kLimbs + 1], neg_inf_ += words[kLimbs + 2];
  if (++pending_ >= kAdditionsBeforeCarry) normalise();
}

// Every limb but the top one to a digit in [0, 2^32), its carry (floor division) into the next;
// the top limb keeps the sign. The same value always gives the same limbs.
void ExactSum::normalise() {
  std::int64_t carry = 0;
  for (std::size_t i = 0; i + 1 < kLimbs; ++i) {
    const std::int64_t v = limb_[i] + carry;
    limb_[i] = v & kDigitMask;
    carry = v >> kDigitBits;  // arithmetic shift: floor(v / 2^32)
  }
  limb_[kLimbs - 1] += carry;
  pending_ = 0;
}

std::array<std::int64_t, ExactSum::kWords> ExactSum::words() const {
  ExactSum c = *this;
  c.normalise();
  std::array<std::int64_t, kWords> w{};
  for (std::size_t i = 0; i < kLimbs; ++i) w[i] = c.limb_[i];
  w[kLimbs] = c.nan_, w[kLimbs + 1] = c.pos_inf_, w[kLimbs + 2] = c.neg_inf_;
  return w;
}

double ExactSum::value() const {
  if (nan_ > 0 || (pos_inf_ > 0 && neg_inf_ > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (pos_inf_ > 0) return std::numeric_limits<double>::infinity();
  if (neg_inf_ > 0) return -std::numeric_limits<double>::infinity();
  ExactSum c = *this;
  c.normalise();
  const bool negative = c.limb_[kLimbs - 1] < 0;
  if (negative) {  // the magnitude: every limb negated, normalised again (the top limb then >= 0)
    for (std::int64_t& l : c.limb_) l = -l;
    c.normalise();
  }
  std::size_t top = kLimbs;
  while (top > 0 && c.limb_[top - 1] == 0) --top;
  if (top == 0) return 0.0;
  // The top three digits (at least 65 significant bits when there are three), and a sticky bit
  // for anything below them, round to the same double as the whole number: the conversion of the
  // 128-bit integer rounds to nearest, ties to even.
  const std::size_t low = top >= 3 ? top - 3 : 0;
  Wide q = 0;
  for (std::size_t i = top; i-- > low;) q = (q << kDigitBits) | static_cast<Wide>(c.limb_[i]);
  for (std::size_t i = 0; i < low; ++i)
    if (c.limb_[i] != 0) {
      q |= 1;
      break;
    }
  // (a result in the subnormal range is rounded twice, here and by ldexp: within one ulp, and
  // still a function of the exact sum alone)
  const double magnitude = std::ldexp(static_cast<double>(q), kDigitBits * static_cast<int>(low) - kBias);
  return negative ? -magnitude : magnitude;
}

void ExactSum::clear() { *this = ExactSum{}; }

}  // namespace tactus::solver
