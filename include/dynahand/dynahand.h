/// @file
/// Everything of dynahand's public API in one include, ordered as the pipeline: core
/// vocabulary, depth sources, the point cloud, physics, the hand model, synthetic data, the
/// learned detector, the tracker, input/output and evaluation, the playground.
/// `#include <dynahand/dynahand.h>` and link `dynahand::dynahand` (docs/architecture.md).
/// Units: metres, seconds, radians; camera frame as OpenCV (x right, y down, z forward).
#pragma once

// Core vocabulary and depth sources.
#include "dynahand/atomic_file.h"
#include "dynahand/camera.h"
#include "dynahand/core.h"
#include "dynahand/depth_frame.h"
#include "dynahand/sequence.h"
// Depth frame to point cloud.
#include "dynahand/boundary_planes.h"
#include "dynahand/cloud.h"
#include "dynahand/hand_split.h"
#include "dynahand/voxel_grid.h"
// Physics.
#include "dynahand/convex_shape.h"
#include "dynahand/physics_angles.h"
#include "dynahand/physics_world.h"
// The hand model.
#include "dynahand/hand_size.h"
#include "dynahand/model.h"
#include "dynahand/model_fit.h"
#include "dynahand/model_intel.h"
#include "dynahand/model_pose.h"
#include "dynahand/model_world.h"
// Synthetic sequences.
#include "dynahand/synth.h"
#include "dynahand/synth_render.h"
#include "dynahand/synth_sensor.h"
// The learned keypoint detector.
#include "dynahand/detector.h"
#include "dynahand/detector_data.h"
// The tracker, its outputs and their evaluation (pictures, the benchmark suites).
#include "dynahand/keypoint_io.h"
#include "dynahand/metrics.h"
#include "dynahand/track_io.h"
#include "dynahand/tracker.h"
// The physics playground.
#include "dynahand/playground.h"
#include "dynahand/playground_io.h"
