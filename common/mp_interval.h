// vobb::MpInterval — a closed interval of binary floating-point numbers (MPFR) of 128 bits, or
// 256 within a Precision scope, every operation rounded outward. Whatever values lie in the
// operands, the exact result of the same operation on them lies in the result: a chain of
// operations encloses the exact value of the same expression in rationals. Holds its significands
// inline: no allocation.
//
// It is certify's filter (exact/filtered_solver.h) and the polyhedral overlap's second tier
// (fast/poly_overlap.h): 128 bits tell apart boxes whose faces touch mesh vertices (1e-17 apart
// in relative terms) and leave a sum's enclosure within one double's rounding cell except at
// rounding ties; 256 bits serve where near-degenerate cuts (slivers between nearly coplanar
// planes) widen an enclosure past that. A sign it cannot decide throws Undecided; the caller
// then computes in rationals.
#pragma once

#include <gmp.h>
#include <mpfr.h>

#include <string>
#include <utility>

#include "common/exact_predicates.h"

namespace vobb {

// A decision the enclosure cannot take (it holds 0 and other values).
struct Undecided {};

class MpInterval {
 public:
  static constexpr mpfr_prec_t kPrec = 128;     // the precision of results by default
  static constexpr mpfr_prec_t kMaxPrec = 256;  // within a Precision scope

  // Results (and conversions) made on this thread while it lives have `bits` of precision
  // (kPrec or kMaxPrec); operands of any precision mix.
  class Precision {
   public:
    explicit Precision(mpfr_prec_t bits);
    ~Precision();
    Precision(const Precision&) = delete;
    Precision& operator=(const Precision&) = delete;

   private:
    mpfr_prec_t saved_;
  };
  mpfr_prec_t bits() const { return mpfr_get_prec(lo_); }

  MpInterval() { init(); }  // [0, 0]
  MpInterval(double x);     // NOLINT: exact (a double fits in 128 bits)
  MpInterval(int x) : MpInterval(static_cast<double>(x)) {}  // NOLINT
  explicit MpInterval(const Rational& q);                    // the two 128-bit numbers around q
  MpInterval(const MpInterval& o);
  MpInterval& operator=(const MpInterval& o);

  friend MpInterval operator+(const MpInterval& a, const MpInterval& b);
  friend MpInterval operator-(const MpInterval& a, const MpInterval& b);
  friend MpInterval operator*(const MpInterval& a, const MpInterval& b);
  // Throws Undecided where b's enclosure holds 0.
  friend MpInterval operator/(const MpInterval& a, const MpInterval& b);
  friend MpInterval operator-(const MpInterval& a);
  MpInterval& operator+=(const MpInterval& b) { return *this = *this + b; }
  MpInterval& operator-=(const MpInterval& b) { return *this = *this - b; }
  friend MpInterval abs(const MpInterval& a);

  // -1, 0 or +1 where the enclosure decides it (0 only for [0, 0]); otherwise throws Undecided.
  int sign() const;
  // Outward doubles: inf() <= every value inside <= sup().
  double inf() const;
  double sup() const;
  // The double nearest to every value inside, where one double is (both ends round to it).
  bool nearest(double* d) const;
  // The ends, exactly.
  Rational lo_rational() const;
  Rational hi_rational() const;
  bool contains(const Rational& q) const;
  // The ends as MPFR's exact hexadecimal text ("%Ra"), and back; false for text that is not
  // two such numbers with lo <= hi.
  void to_text(std::string* lo, std::string* hi) const;
  static bool from_text(const std::string& lo, const std::string& hi, MpInterval* out);
  // For the tests: [lo, lo].
  MpInterval collapsed_for_tests() const;

 private:
  static constexpr int kLimbs = (kMaxPrec + GMP_NUMB_BITS - 1) / GMP_NUMB_BITS;
  void init(mpfr_prec_t bits);
  void init();  // at this thread's precision
  mpfr_t lo_, hi_;
  mp_limb_t lo_limbs_[kLimbs], hi_limbs_[kLimbs];
};

// Signs and double bounds for the clipping code that is generic over the number type
// (common/box_frame_clip.h, common/cell_clip.h).
namespace box_clip {
template <class NT>
struct ClipTraits;
template <>
struct ClipTraits<MpInterval> {
  static int sign(const MpInterval& x) { return x.sign(); }  // throws Undecided
};
}  // namespace box_clip
namespace cell_clip {
template <class NT>
struct NumberBounds;
template <>
struct NumberBounds<MpInterval> {
  static std::pair<double, double> of(const MpInterval& x) { return {x.inf(), x.sup()}; }
};
}  // namespace cell_clip

}  // namespace vobb
