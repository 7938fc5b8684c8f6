# The package's Python module (hameritt.lockstep), installed by catkin_python_setup() beside
# the generated messages (hameritt.msg, hameritt.srv).
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(packages=["hameritt"], package_dir={"": "src"}))
