// Per-pixel coverage lists of the anti-aliased hemicube (Chandran, Kiran, Phani and Rai, section 3.2.1):
// insertion sort into small pooled arrays. See coverage_list.h for the rules and the layout.
#include "aarad/formfactor/coverage_list.h"

#include <algorithm>
#include <cmath>

namespace aarad::formfactor {

void PartialLists::reset(std::size_t pixels) {
  if (!clean_) std::fill(head_.begin(), head_.end(), kNil);
  if (head_.size() < pixels) head_.resize(pixels, kNil);
  used_ = 0;
  clean_ = false;
}

void PartialLists::grow(std::size_t cells) {
  pool_.resize(std::max<std::size_t>(used_ + cells, 2 * pool_.size()));
}

std::uint32_t PartialLists::allocate(std::uint32_t capacity) {
  if (used_ + 1 + capacity > pool_.size()) grow(1 + capacity);
  const auto list = static_cast<std::uint32_t>(used_);
  used_ += 1 + capacity;
  return list;
}

bool PartialLists::insert_into(std::uint32_t& list, const CoverageEntry& entry) {
  Cell* cells = &pool_[list];
  const std::uint32_t count = cells[0].header.count;
  const std::uint32_t full = cells[0].header.full;
  const std::uint32_t surface = entry.surface;
  std::uint32_t position = count + 1;
  double group_sum = 0.0;
  bool joins = surface == cells[0].header.last_surface;
  if (joins) {
    // The group that took the last entry: go after its last piece.
    position = cells[0].header.last_end;
    group_sum = cells[0].header.last_sum;
  } else {
    // The group of the entry's surface, if the list has one; meanwhile the depth position (the first group head
    // behind the entry: positions are decided at group heads only, so groups stay contiguous).
    std::uint32_t prev_surface = kNoSurface, k = 1;
    for (; k <= count; ++k) {
      const CoverageEntry& e = cells[k].entry;
      if (e.surface == surface) break;
      if (position > count && e.surface != prev_surface &&
          (e.depth > entry.depth || (e.depth == entry.depth && in_front_at_equal_key(surface, e.surface))))
        position = k;
      prev_surface = e.surface;
    }
    joins = k <= count;
    if (joins) {
      // Join the group, after its last piece.
      do {
        group_sum += cells[k].entry.coverage;
        ++k;
      } while (k <= count && cells[k].entry.surface == surface);
      position = k;
    } else if (full != 0 && position > full && hidden_by_full_group(cells[full].entry, entry)) {
      return false;  // behind the covering group
    }
  }
  group_sum += entry.coverage;
  if (count == cells[0].header.capacity) {
    // Move the list to a block twice as large at the end of the pool.
    const std::uint32_t capacity = 2 * count;
    const std::uint32_t moved = allocate(capacity);
    cells = &pool_[list];
    std::copy(cells, cells + 1 + count, &pool_[moved]);
    pool_[moved].header.capacity = capacity;
    list = moved;
    cells = &pool_[moved];
  }
  // Insertion sort: shift the entries behind one place back.
  for (std::uint32_t i = count; i >= position; --i) cells[i + 1] = cells[i];
  cells[position].entry = entry;
  Header& header = cells[0].header;
  header.count = count + 1;
  if (full != 0 && position <= full) header.full = full + 1;
  if (joins && group_sum >= kFullCoverage) {
    // Everything behind a covering group is hidden, but for the groups whose range reaches into its own.
    std::uint32_t head = position;
    while (head > 1 && cells[head - 1].entry.surface == surface) --head;
    std::uint32_t kept = position;
    bool keep = false;
    for (std::uint32_t i = position + 1; i <= header.count; ++i) {
      if (cells[i].entry.surface != cells[i - 1].entry.surface)
        keep = !hidden_by_full_group(cells[head].entry, cells[i].entry);
      if (keep) cells[++kept] = cells[i];
    }
    header.count = kept;
    if (header.full == 0 || header.full > head) header.full = head;
  }
  header.last_surface = surface;
  header.last_end = position + 1;
  header.last_sum = group_sum;
  return true;
}

void CoverageArena::reset(std::size_t pixels) {
  if (!clean_) std::fill(depth_.begin(), depth_.end(), kFar);
  if (depth_.size() < pixels) {
    depth_.resize(pixels, kFar);
    receiver_.resize(pixels, 0);
    full_meta_.resize(pixels);
  }
  lists_.reset(pixels);
  pixels_ = pixels;
  entries_ = 0;
  clean_ = false;
}

void StagedCoverageArena::reset(int width, int height) {
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (!clean_) {
    std::fill(depth_.begin(), depth_.end(), kFar);
    std::fill(surface_.begin(), surface_.end(), kNoPartial);
    std::fill(covered_.begin(), covered_.end(), 0.0);
    for (std::vector<Staged>& stage : stage_) stage.clear();
  }
  // Two columns more than the face: insert() prefetches two columns ahead.
  if (depth_.size() < pixels + 2 * height) {
    depth_.resize(pixels + 2 * height, kFar);
    receiver_.resize(pixels + 2 * height, 0);
    surface_.resize(pixels + 2 * height, kNoPartial);
  }
  // Blocks of 2^k whole columns, as many as fit in kBlockPixels (at least one column).
  block_shift_ = 0;
  while ((static_cast<std::size_t>(height) << (block_shift_ + 1)) <= kBlockPixels && (1 << block_shift_) < width)
    ++block_shift_;
  height_ = static_cast<std::size_t>(height);
  block_pixels_ = height_ << block_shift_;
  blocks_ = (static_cast<std::size_t>(width) + (std::size_t{1} << block_shift_) - 1) >> block_shift_;
  one_surface_pixels_ = blocks_ == 1;
  if (one_surface_pixels_ && covered_.size() < block_pixels_) covered_.resize(block_pixels_, 0.0);
  if (stage_.size() < blocks_) stage_.resize(blocks_);
  pixels_ = pixels;
  clean_ = false;
}

}  // namespace aarad::formfactor
