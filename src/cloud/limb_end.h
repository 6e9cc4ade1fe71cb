// The free end of a limb: where the hand is when the nearest point is not on it.
//
// The nearest sufficiently large volume is the hand when the hand is held toward the
// camera. When the forearm points at the camera (third-person view, the arm reaching in
// from the image border), the nearest point is on the forearm and a hand-sized ball
// around it holds forearm and palm but cuts the fingers off. A limb is attached to the
// body at one end: its surface continues out of view (the image border) or beyond any
// hand-sized ball (to the elbow, the torso). The hand is the other, free end: the point
// of the limb's surface farthest along the surface from every attachment.
#pragma once

#include <cstdint>
#include <vector>

#include "cloud/region_grow.h"

namespace dynahand::cloud {

class LimbEndFinder {
 public:
  void reserve(std::size_t cells, int maxWidth, int maxHeight);

  // Explores the surface connected to `seed` (neighbours within the step rule) inside a
  // ball of limbRadiusM around the seed's point. Its attachments are the connected cells beyond the
  // ball, the cells within borderMarginPixels of the image border, and the cells nearer than
  // nearCutDepthM (m) where the surface, coming nearer, runs into missing data (cut off by the
  // sensor's near range). Of separate attachments only the body's side is kept (keepBodySide).
  // Returns the cell of the surface farthest from every attachment kept, measured along the
  // surface, or -1 when the surface has no attachment (a hand on its own: its nearest point is
  // fine). planeCells (optional, per grid cell, nonzero: a sample of a support plane
  // taken out of the grid): a surface with no other attachment is attached where it meets such
  // cells (a forearm rising from a table, which hides the rest of the arm).
  int find(const DepthGrid& grid, const Intrinsics& k, int seed, const DepthStepRule& rule,
           float limbRadiusM, int borderMarginPixels, float nearCutDepthM,
           const std::uint8_t* planeCells = nullptr);

  // Whether the last find() reached grid cell `cell` (on the limb's surface inside its ball).
  bool reached(int cell) const {
    return cell >= 0 && static_cast<std::size_t>(cell) < state_.size() &&
           state_[static_cast<std::size_t>(cell)] != 0;
  }

 private:
  // find's stages after the surface and its attachments are found. keepBodySide: of several
  // separate attachments (of any kind: the image border, the ball's edge, a near cut), the
  // lowest in the image is where the limb is attached, as the body is below the view of a desk
  // or a head-mounted camera; one whose mean row lies higher by more than separationM (m, at
  // the seed's depth depthM) is not an attachment (a hand going on out of view, a forearm
  // leaving the ball toward the fist). Then steps along the surface from the attachments kept
  // (breadth-first), then the cell farthest from all of them.
  void keepBodySide(const DepthGrid& grid, const Intrinsics& k, float depthM, float separationM);
  void stepFromAttachments(const DepthGrid& grid, const Intrinsics& k, const DepthStepRule& rule);
  int farthestCell(int width) const;

  std::vector<int> steps_;           // (cells) steps along the surface from an attachment, -1
  std::vector<std::uint8_t> state_;  // (cells) 0 = unseen, 1 = on the surface, 2 = attachment
  // Packed cells (j << 16 | i):
  std::vector<std::int32_t> cells_;          // the surface's cells in discovery order
  std::vector<std::int32_t> queue_;          // breadth-first order from the attachments
  std::vector<std::int32_t> planeContacts_;  // surface cells next to a support plane's cells
  std::vector<std::int32_t> stack_;          // flood fill over the attachments
  std::vector<int> group_;                   // (cells) connected group of an attachment, -1
  std::vector<float> groupRows_;             // (groups) mean row (cells)
  std::vector<int> groupCounts_;             // (groups) cells
  std::vector<float> columnX_;               // (width) (u - cx) / fx of each column
  std::vector<float> rowY_;                  // (height) (v - cy) / fy of each row
};

}  // namespace dynahand::cloud
