#include "common/mp_interval.h"

#include <cstdlib>
#include <cstring>

#include "common/status.h"

namespace vobb {

namespace {
thread_local mpfr_prec_t current_bits = MpInterval::kPrec;
}  // namespace

MpInterval::Precision::Precision(mpfr_prec_t bits) : saved_(current_bits) {
  VOBB_ASSERT(bits >= MPFR_PREC_MIN && bits <= kMaxPrec, "MpInterval precision within its storage");
  current_bits = bits;
}

MpInterval::Precision::~Precision() { current_bits = saved_; }

void MpInterval::init(mpfr_prec_t bits) {  // [+0, +0]
  mpfr_custom_init(lo_limbs_, bits);
  mpfr_custom_init(hi_limbs_, bits);
  mpfr_custom_init_set(lo_, MPFR_ZERO_KIND, 0, bits, lo_limbs_);
  mpfr_custom_init_set(hi_, MPFR_ZERO_KIND, 0, bits, hi_limbs_);
}

void MpInterval::init() { init(current_bits); }

MpInterval::MpInterval(double x) {
  init();
  mpfr_set_d(lo_, x, MPFR_RNDD);
  mpfr_set_d(hi_, x, MPFR_RNDU);
}

MpInterval::MpInterval(const Rational& q) {
  init();
  mpfr_set_q(lo_, q.get_mpq_t(), MPFR_RNDD);
  mpfr_set_q(hi_, q.get_mpq_t(), MPFR_RNDU);
}

MpInterval::MpInterval(const MpInterval& o) {
  // A copy keeps o's precision: the significands copy as they are.
  const mpfr_prec_t bits = o.bits();
  const size_t bytes = mpfr_custom_get_size(bits);
  std::memcpy(lo_limbs_, o.lo_limbs_, bytes);
  std::memcpy(hi_limbs_, o.hi_limbs_, bytes);
  mpfr_custom_init_set(lo_, mpfr_custom_get_kind(o.lo_), mpfr_custom_get_exp(o.lo_), bits,
                       lo_limbs_);
  mpfr_custom_init_set(hi_, mpfr_custom_get_kind(o.hi_), mpfr_custom_get_exp(o.hi_), bits,
                       hi_limbs_);
}

MpInterval& MpInterval::operator=(const MpInterval& o) {
  if (this != &o) {
    // Takes o's precision where it is more than this one's; rounded outward otherwise.
    if (o.bits() > bits()) init(o.bits());
    mpfr_set(lo_, o.lo_, MPFR_RNDD);
    mpfr_set(hi_, o.hi_, MPFR_RNDU);
  }
  return *this;
}

MpInterval operator+(const MpInterval& a, const MpInterval& b) {
  MpInterval r;
  mpfr_add(r.lo_, a.lo_, b.lo_, MPFR_RNDD);
  mpfr_add(r.hi_, a.hi_, b.hi_, MPFR_RNDU);
  return r;
}

MpInterval operator-(const MpInterval& a, const MpInterval& b) {
  MpInterval r;
  mpfr_sub(r.lo_, a.lo_, b.hi_, MPFR_RNDD);
  mpfr_sub(r.hi_, a.hi_, b.lo_, MPFR_RNDU);
  return r;
}

MpInterval operator-(const MpInterval& a) {
  MpInterval r;
  mpfr_neg(r.lo_, a.hi_, MPFR_RNDD);  // exact
  mpfr_neg(r.hi_, a.lo_, MPFR_RNDU);
  return r;
}

MpInterval operator*(const MpInterval& x, const MpInterval& y) {
  // [a, b] [c, d] by the signs of the ends: the extreme products are the ones named.
  const mpfr_srcptr a = x.lo_, b = x.hi_, c = y.lo_, d = y.hi_;
  MpInterval r;
  auto set = [&](mpfr_srcptr lo1, mpfr_srcptr lo2, mpfr_srcptr hi1, mpfr_srcptr hi2) {
    mpfr_mul(r.lo_, lo1, lo2, MPFR_RNDD);
    mpfr_mul(r.hi_, hi1, hi2, MPFR_RNDU);
  };
  if (mpfr_sgn(a) >= 0) {
    if (mpfr_sgn(c) >= 0)
      set(a, c, b, d);
    else if (mpfr_sgn(d) <= 0)
      set(b, c, a, d);
    else
      set(b, c, b, d);
  } else if (mpfr_sgn(b) <= 0) {
    if (mpfr_sgn(c) >= 0)
      set(a, d, b, c);
    else if (mpfr_sgn(d) <= 0)
      set(b, d, a, c);
    else
      set(a, d, a, c);
  } else {  // a < 0 < b
    if (mpfr_sgn(c) >= 0)
      set(a, d, b, d);
    else if (mpfr_sgn(d) <= 0)
      set(b, c, a, c);
    else {
      MpInterval s;
      mpfr_mul(r.lo_, a, d, MPFR_RNDD);
      mpfr_mul(s.lo_, b, c, MPFR_RNDD);
      mpfr_min(r.lo_, r.lo_, s.lo_, MPFR_RNDD);
      mpfr_mul(r.hi_, a, c, MPFR_RNDU);
      mpfr_mul(s.hi_, b, d, MPFR_RNDU);
      mpfr_max(r.hi_, r.hi_, s.hi_, MPFR_RNDU);
    }
  }
  return r;
}

MpInterval operator/(const MpInterval& x, const MpInterval& y) {
  const mpfr_srcptr a = x.lo_, b = x.hi_, c = y.lo_, d = y.hi_;
  MpInterval r;
  auto set = [&](mpfr_srcptr lo1, mpfr_srcptr lo2, mpfr_srcptr hi1, mpfr_srcptr hi2) {
    mpfr_div(r.lo_, lo1, lo2, MPFR_RNDD);
    mpfr_div(r.hi_, hi1, hi2, MPFR_RNDU);
  };
  if (mpfr_sgn(c) > 0) {
    if (mpfr_sgn(a) >= 0)
      set(a, d, b, c);
    else if (mpfr_sgn(b) <= 0)
      set(a, c, b, d);
    else
      set(a, c, b, c);
  } else if (mpfr_sgn(d) < 0) {
    if (mpfr_sgn(a) >= 0)
      set(b, d, a, c);
    else if (mpfr_sgn(b) <= 0)
      set(b, c, a, d);
    else
      set(b, d, a, d);
  } else {
    throw Undecided{};
  }
  return r;
}

MpInterval abs(const MpInterval& x) {
  if (mpfr_sgn(x.lo_) >= 0) return x;
  if (mpfr_sgn(x.hi_) <= 0) return -x;
  MpInterval r;  // [0, max(-lo, hi)]
  mpfr_neg(r.hi_, x.lo_, MPFR_RNDU);
  mpfr_max(r.hi_, r.hi_, x.hi_, MPFR_RNDU);
  return r;
}

int MpInterval::sign() const {
  if (mpfr_sgn(lo_) > 0) return 1;
  if (mpfr_sgn(hi_) < 0) return -1;
  if (mpfr_zero_p(lo_) && mpfr_zero_p(hi_)) return 0;
  throw Undecided{};
}

double MpInterval::inf() const { return mpfr_get_d(lo_, MPFR_RNDD); }
double MpInterval::sup() const { return mpfr_get_d(hi_, MPFR_RNDU); }

bool MpInterval::nearest(double* d) const {
  // Rounding to nearest is monotone: a value between lo and hi rounds between their roundings.
  const double lo = mpfr_get_d(lo_, MPFR_RNDN), hi = mpfr_get_d(hi_, MPFR_RNDN);
  *d = lo == 0 ? 0.0 : lo;  // an exact 0 is +0, as a rational's rounding is
  return lo == hi;
}

Rational MpInterval::lo_rational() const {
  Rational q;
  mpfr_get_q(q.get_mpq_t(), lo_);
  return q;
}

Rational MpInterval::hi_rational() const {
  Rational q;
  mpfr_get_q(q.get_mpq_t(), hi_);
  return q;
}

bool MpInterval::contains(const Rational& q) const {
  return lo_rational() <= q && q <= hi_rational();
}

void MpInterval::to_text(std::string* lo, std::string* hi) const {
  char* s = nullptr;
  mpfr_asprintf(&s, "%Ra", lo_);
  *lo = s;
  mpfr_free_str(s);
  mpfr_asprintf(&s, "%Ra", hi_);
  *hi = s;
  mpfr_free_str(s);
}

bool MpInterval::from_text(const std::string& lo, const std::string& hi, MpInterval* out) {
  MpInterval r;
  r.init(kMaxPrec);  // any number this class wrote reads exactly
  char* end = nullptr;
  // Base 16 with the 0x prefix, as %Ra writes; a number of up to 128 bits reads exactly (an
  // inexact read is a number this class did not write: refused).
  if (lo.empty() || mpfr_strtofr(r.lo_, lo.c_str(), &end, 16, MPFR_RNDD) != 0 || *end != '\0')
    return false;
  if (hi.empty() || mpfr_strtofr(r.hi_, hi.c_str(), &end, 16, MPFR_RNDU) != 0 || *end != '\0')
    return false;
  if (!mpfr_number_p(r.lo_) || !mpfr_number_p(r.hi_) || mpfr_greater_p(r.lo_, r.hi_)) return false;
  *out = r;
  return true;
}

MpInterval MpInterval::collapsed_for_tests() const {
  MpInterval r = *this;
  mpfr_set(r.hi_, r.lo_, MPFR_RNDU);
  return r;
}

}  // namespace vobb
