#include "federation/credit_account.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace haptic::federation {

CreditAccount::Verdict CreditAccount::take(double claimed, std::chrono::steady_clock::time_point now,
                                           const CreditCap& cap) {
  if (!std::isfinite(claimed) || claimed < 0.0) return Verdict::kNotFinite;
  if (!started_) {
    started_ = true;
    bucket_ = cap.burst_J;
  } else {
    const double elapsed = std::max(0.0, std::chrono::duration<double>(now - last_).count());
    bucket_ = std::min(cap.burst_J, bucket_ + cap.max_power_W * elapsed);
    over_ = std::max(0.0, over_ - cap.max_power_W * elapsed);
  }
  last_ = now;
  if (claimed < last_claimed_) {  // the peer's coupling began anew: its count restarts
    last_claimed_ = claimed;
    return Verdict::kCredited;
  }
  const double claim = claimed - last_claimed_;
  last_claimed_ = claimed;
  const double credit = std::min(claim, bucket_);
  bucket_ -= credit;
  credited_ += credit;
  refused_ += claim - credit;
  over_ += claim - credit;
  return over_ > cap.burst_J ? Verdict::kOverCap : Verdict::kCredited;
}

}  // namespace haptic::federation
