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
  ToolScene(const chai3d::cGenericHapticDevicePtr& device, double tool_radius) {
    tool = new chai3d::cToolCursor(&world);
    world.addChild(tool);
    tool->setHapticDevice(device);
    tool->setRadius(tool_radius);
    tool->setWorkspaceRadius(device->getSpecifications().m_workspaceRadius);  // world = device coordinates
  }

  /// A 4r x 4r x 2r box (r = workspace radius) whose top face is at z = -depth r.
  chai3d::cMesh* addBlock(double depth, double stiffness) {
    const double r = tool->getHapticDevice()->getSpecifications().m_workspaceRadius;
    block = new chai3d::cMesh();
    world.addChild(block);
    chai3d::cCreateBox(block, 4 * r, 4 * r, 2 * r);
    block->setLocalPos(0.0, 0.0, -(1.0 + depth) * r);
    block->createAABBCollisionDetector(0.01);  // the tree's margin must cover the tool radius
    block->m_material->setStiffness(stiffness);
    return block;
  }

  void tick() {
    world.computeGlobalPositions(true);
    tool->updateFromDevice();
    tool->computeInteractionForces();
    tool->applyToDevice();
  }
};
