"""Habitat-style MAV simulator shim (DESIGN Section 6).

Modules: scene (semantic meshes, the public face of scene_model, ply,
habitat (PLY + .house), labelled_mesh (mesh + JSON labels), free_space and
ground_truth (export for scoring)), generator (seeded indoor houses, from
furniture and mesh_builder), renderer (one Embree pass per frame through
embree3 or embreex: depth/colour/instance/class images with depth noise;
reference_renderer is the renderer it replaced, kept for tests and
bench_sim), detector (detections from ground truth), mav (kinematic path
follower, sphere collisions), simulator (ROS-free core), node (the
``mav_sim`` ROS node), config (settings with Table I defaults). Only
``node`` imports ROS.
"""
