#include "shle/error.h"
#include "shle/tracker.h"

namespace shle {

std::unique_ptr<Tracker> make_tracker(const std::string& kind, const NccOptions& ncc, const MilOptions& mil) {
  if (kind == "ncc") return std::make_unique<NccTracker>(ncc);
  if (kind == "mil") return std::make_unique<MilTracker>(mil);
  if (kind == "none") return nullptr;
  throw Error("unknown tracker '" + kind + "' (use ncc, mil or none)");
}

}  // namespace shle
