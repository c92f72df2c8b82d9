"""ament_python / pip setup for drd_msgs_py."""

from setuptools import find_packages, setup

PACKAGE = "drd_msgs_py"

setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(exclude=["test", "tests"]),
    package_data={PACKAGE: ["py.typed"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
    ],
    python_requires=">=3.10",
    install_requires=["numpy>=1.24", "rosbags>=0.11"],
    zip_safe=True,
    maintainer="drd_planner maintainers",
    maintainer_email="maintainers@drd-planner.invalid",
    description="Standard ROS 2 message conversions for drd_planner",
    license="BSD-3-Clause",
)
