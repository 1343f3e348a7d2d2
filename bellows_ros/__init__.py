"""
bellows_ros: pneumatic bellows models, identification, model doctor, drivers and ROS 2 nodes.

Layers (each imports only from the ones above it in this list):
models -> identify, doctor -> hardware -> control -> nodes (+ runtime) -> cli.
"""
__version__ = '0.1.0'
