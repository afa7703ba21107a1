#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "core/table_geometry.hpp"

/// Table angles that point a body axis of an IMU up or down: what a `move` step given as
/// `"up": "+x"` is resolved to at plan time, for the station's table and the IMU's mount.
namespace calstand::procedures {

/// A body axis with its direction: `axis` 0, 1, 2 for x, y, z; `sign` +1 or -1.
struct BodyDirection {
  int axis = 2;
  int sign = +1;
  /// "+x" ... "-z".
  std::string text() const;
};

/// "+x", "-x", "+y", "-y", "+z", "-z" (the `up` of a move step); nullopt for anything else.
std::optional<BodyDirection> parse_body_direction(std::string_view text);

/// Table angles of one pointing [deg].
struct TableAngles {
  double outer_deg = 0.0;
  double inner_deg = 0.0;
};

/// The angles that put body direction `up` along the local vertical, Up (C_LB^T (0, 0, 1) =
/// up within 1e-6): searched over multiples of 90 deg, then of 45 deg, in (-180, 180], the
/// smallest total rotation from (0, 0) first, so that the result does not depend on where the
/// table happens to be. nullopt when no such angles exist: the table's axes and the mount decide
/// which pointings exist (a table whose outer axis is vertical cannot tip anything).
std::optional<TableAngles> point_up(const core::TableGeometry& geometry, const BodyDirection& up);

}  // namespace calstand::procedures
