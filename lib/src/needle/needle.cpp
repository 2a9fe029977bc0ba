#include <incise/core/error.hpp>
#include <incise/needle/needle.hpp>

#include <cmath>
#include <string>

namespace incise::needle {

NeedlePose NeedlePose::make(const Vec2& tip, const Vec2& direction, double length) {
  NeedlePose p;
  p.tip = tip;
  p.direction = direction;
  p.length = length;
  p.validate();
  p.direction = direction.normalized();
  return p;
}

void NeedlePose::validate() const {
  INCISE_CHECK_PARAM(tip.allFinite(), "needle tip must be finite");
  INCISE_CHECK_PARAM(direction.allFinite() && direction.norm() > 0.0,
                     "needle direction must be finite and non-zero");
  INCISE_CHECK_PARAM(std::isfinite(length) && length > 0.0,
                     "needle length must be finite and > 0, got " + std::to_string(length));
}

NeedleCoordinates NeedlePose::coordinates(const Vec2& x) const {
  NeedleCoordinates c;
  c.s = (tip - x).dot(tangent());
  c.perp = (x - tip).dot(normal());
  return c;
}

Vec2 NeedlePose::point(const NeedleCoordinates& c) const {
  return tip - c.s * tangent() + c.perp * normal();
}

const char* to_string(NodeState s) {
  switch (s) {
    case NodeState::kStick: return "stick";
    case NodeState::kSlip: return "slip";
  }
  return "?";
}

}  // namespace incise::needle
