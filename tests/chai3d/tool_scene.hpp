#pragma once
// A headless CHAI3D scene built the way the GLFW examples build theirs: a world, optionally a rigid
// block below the workspace centre (a mesh: CHAI3D's finger proxy renders it), a stock cToolCursor
// on the device with world units = device units, and the haptic loop's four calls per tick. No GL.
#include "chai3d.h"

struct ToolScene {
  chai3d::cWorld world;
  chai3d::cToolCursor* tool = nullptr;  // owned by the world
  chai3d::cMesh* block = nullptr;

  /// The tool is set up but not started. Blocks must be added before the first tick.
  /// world_radius: the workspace's radius in world units (0: world = device coordinates; 1: as
  /// CHAI3D's examples map it, which scales lengths, and so CHAI3D's proxy tolerance, by that).
  ToolScene(const chai3d::cGenericHapticDevicePtr& device, double tool_radius, double world_radius = 0.0) {
    tool = new chai3d::cToolCursor(&world);
    world.addChild(tool);
    tool->setHapticDevice(device);
    tool->setRadius(tool_radius);
    const double r = device->getSpecifications().m_workspaceRadius;
    tool->setWorkspaceRadius(world_radius > 0.0 ? world_radius : r);
  }
  /// World units per device metre.
  double scale() { return tool->getWorkspaceScaleFactor(); }

  /// A 4r x 4r x 2r box (r = workspace radius) whose top face is at z = -depth r; stiffness in the
  /// device frame [N/m] (the material's is that over scale()).
  chai3d::cMesh* addBlock(double depth, double stiffness) {
    const double r = tool->getHapticDevice()->getSpecifications().m_workspaceRadius * scale();
    block = new chai3d::cMesh();
    world.addChild(block);
    chai3d::cCreateBox(block, 4 * r, 4 * r, 2 * r);
    block->setLocalPos(0.0, 0.0, -(1.0 + depth) * r);
    block->createAABBCollisionDetector(0.01 * scale());  // the tree's margin must cover the tool radius
    block->m_material->setStiffness(stiffness / scale());
    return block;
  }

  void tick() {
    world.computeGlobalPositions(true);
    tool->updateFromDevice();
    tool->computeInteractionForces();
    tool->applyToDevice();
  }
};
