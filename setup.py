# Installs the Python package (simulator, evaluation) through catkin.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(
    packages=["semantic_exploration", "semantic_exploration.sim", "semantic_exploration.eval"],
    package_dir={"": "src"},
))
