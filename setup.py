"""Build script shared by pip (PEP 517, metadata in pyproject.toml) and colcon (ament_python).

colcon's ament_python build still drives ``setup.py``; the data files below give the ROS layout
(share/bt_nav/{package.xml,trees,launch,config,sim/worlds} and the ament index marker), while the
console scripts (declared in pyproject.toml) land in lib/bt_nav through setup.cfg, so that
``ros2 run bt_nav executive`` works.
"""

from glob import glob

from setuptools import setup

PACKAGE = "bt_nav"

setup(
    name=PACKAGE,
    packages=[PACKAGE, f"{PACKAGE}.behaviours", f"{PACKAGE}.sim"],
    package_data={f"{PACKAGE}.sim": ["worlds/*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE}"]),
        (f"share/{PACKAGE}", ["package.xml"]),
        (f"share/{PACKAGE}/trees", glob("trees/*.xml")),
        (f"share/{PACKAGE}/launch", glob("launch/*.launch.py")),
        (f"share/{PACKAGE}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE}/sim/worlds", glob("sim/worlds/*.yaml")),
    ],
    zip_safe=False,
)
