// Rows of form factors per shooting patch, within a memory budget (factor_cache.h).
#include "aarad/refine/factor_cache.h"

#include <utility>

namespace aarad::refine {

const FactorRow* FactorCache::find(mesh::NodeId patch, const void* source) {
  if (source != source_) return nullptr;
  const auto it = rows_.find(patch);
  if (it == rows_.end()) return nullptr;
  it->second.last_use = ++clock_;
  return &it->second;
}

FactorRow FactorCache::take(mesh::NodeId patch) {
  const auto it = rows_.find(patch);
  if (it == rows_.end()) return {};
  bytes_ -= bytes_of(it->second);
  FactorRow row = std::move(it->second);
  rows_.erase(it);
  return row;
}

void FactorCache::store(mesh::NodeId patch, const void* source, FactorRow row) {
  if (!enabled()) return;
  if (source != source_) {
    clear();
    source_ = source;
  }
  if (const auto old = rows_.find(patch); old != rows_.end()) drop(old);
  const std::size_t size = bytes_of(row);
  if (size > budget_) return;
  // The least recently used first; last_use is unique, so the order does not depend on the map's.
  while (bytes_ + size > budget_) {
    auto oldest = rows_.begin();
    for (auto it = rows_.begin(); it != rows_.end(); ++it)
      if (it->second.last_use < oldest->second.last_use) oldest = it;
    drop(oldest);
  }
  row.last_use = ++clock_;
  bytes_ += size;
  rows_.emplace(patch, std::move(row));
}

void FactorCache::clear() {
  rows_.clear();
  bytes_ = 0;
}

void FactorCache::drop(std::unordered_map<mesh::NodeId, FactorRow>::iterator row) {
  bytes_ -= bytes_of(row->second);
  rows_.erase(row);
}

}  // namespace aarad::refine
