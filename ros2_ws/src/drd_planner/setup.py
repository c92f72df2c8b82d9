"""ament_python / pip setup for drd_planner."""

from glob import glob
from os.path import relpath

from setuptools import find_packages, setup

PACKAGE = "drd_planner"
# The shipped trees and bags live at the repository root (../../../ from here); a source checkout or the
# Docker image has them there, an sdist does not (then the node takes tree file paths instead of names).
SHIPPED = {kind: sorted(glob(f"../../../{kind}/*.{ext}")) for kind, ext in (("trees", "npz"), ("bags", "mcap"))}
# The repository's LICENSE (BSD-3-Clause, as package.xml says), installed with package.xml where present.
LICENSE = [relpath(f) for f in glob("../../../LICENSE")]

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "tests"]),
    package_data={PACKAGE: ["py.typed"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml", *LICENSE]),
        (f"share/{PACKAGE}/launch", glob("launch/*.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        *((f"share/{PACKAGE}/{kind}", [relpath(f) for f in files]) for kind, files in SHIPPED.items() if files),
    ],
    python_requires=">=3.10",
    install_requires=[
        "numpy>=1.24",
        "scipy>=1.10",
        "networkx>=3.0",
        "tqdm>=4.60",
        "PyYAML>=6.0",
        "python-fcl>=0.7",
        "trimesh>=4.0",
        "dask[distributed]>=2024.1",
        "yourdfpy>=0.0.56",
        "rosbags>=0.11",
        "rasterio>=1.4.4,<2",
        "pyproj>=3.7.2,<4",
        "shapely>=2.0,<3",
        "osmium>=4.3.2,<5",
        "threadpoolctl>=3.8",
        "typing_extensions>=4.6",
        "drd_msgs_py",
    ],
    extras_require={
        "plots": ["matplotlib>=3.6"],
        "test": ["pytest>=7", "hypothesis>=6.80"],
        "peer": ["ompl==1.7.0"],
    },
    zip_safe=True,
    maintainer="drd_planner maintainers",
    maintainer_email="maintainers@drd-planner.invalid",
    description="DiRECt + BiSECt Bayesian active edge evaluation planner",
    license="BSD-3-Clause",
    entry_points={
        "console_scripts": [
            "drd = drd_planner.cli.main:main",
            "planner_node = drd_planner.ros.planner_node:main",
            "drd_replay = drd_planner.cli.replay:main",
            "planner_demo = drd_planner.cli.planner_demo:main",
            "drd_map_server = drd_planner.cli.map_server:main",
        ],
    },
)
