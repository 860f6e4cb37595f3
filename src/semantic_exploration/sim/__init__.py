"""Habitat-style MAV simulator shim (DESIGN Section 6).

Modules: scene (semantic meshes: Habitat PLY + .house, mesh + JSON labels,
ground-truth export), generator (seeded indoor houses), renderer (Embree
depth/colour/instance/class images with depth noise), detector (detections
from ground truth), mav (kinematic path follower, sphere collisions),
simulator (ROS-free core), node (the ``mav_sim`` ROS node), config (settings
with Table I defaults). Only ``node`` imports ROS.
"""
