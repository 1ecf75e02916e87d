#pragma once
// What a peer may be credited: the energy another site says its coupling sent this one (its
// cumulative `sent`, docs/federation.md, "The passivity layer") is the only way a peer can raise
// what this site's passivity layer lets its user be given, so a peer that lies about it could give
// the user any energy. Each coupling's account credits the peer's totals at most at a stated rate
// (a token bucket: CreditCap's burst at once, its power sustained), and says when the peer's books
// do not add up — a total that is not a finite, non-negative number, or claims beyond the cap
// that add up to more than a burst (they drain at the cap's power) — so that the relay cuts the
// peer off. An honest peer sends what its users put in, which stays far under the cap.
//
// Off the loop: the relay's thread keeps one account per coupling and hands the loop the credited
// total in place of the claimed one.

#include <chrono>
#include <string>

#include "federation/options.hpp"

namespace haptic::federation {

class CreditAccount {
 public:
  enum class Verdict {
    kCredited,   // the total was taken (all of it, or up to the cap)
    kNotFinite,  // a NaN, an infinity or a negative total: the books do not add up
    kOverCap,    // claims beyond the cap added up to more than a burst: the books do not add up
  };

  /// The peer's cumulative total `claimed` (J) as it arrived at `now`. A total below the last one
  /// starts the peer's count anew (its coupling restarted) and credits nothing.
  Verdict take(double claimed, std::chrono::steady_clock::time_point now, const CreditCap& cap);
  /// What the loop may take as the peer's cumulative total: never decreases. J.
  double credited() const { return credited_; }
  /// Claimed and not credited, cumulative. J.
  double refused() const { return refused_; }

 private:
  bool started_ = false;
  std::chrono::steady_clock::time_point last_;
  double bucket_ = 0.0;        // credit available now. J
  double over_ = 0.0;          // claims beyond the cap, draining at its power. J
  double last_claimed_ = 0.0;  // J
  double credited_ = 0.0;      // J
  double refused_ = 0.0;       // J
};

}  // namespace haptic::federation
