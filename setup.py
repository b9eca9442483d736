"""Build script shared by pip (PEP 517, metadata in pyproject.toml) and colcon (ament_python).

colcon's ament_python build still drives ``setup.py``; the data files below give the ROS layout
(share/bt_nav/{package.xml,trees,launch,config,sim/worlds} and the ament index marker), while
console scripts land in lib/bt_nav through setup.cfg so that ``ros2 run bt_nav executive`` works.
"""

from glob import glob

from setuptools import setup

PACKAGE = "bt_nav"

ENTRY_POINTS = [
    "bt-nav = bt_nav.cli:main",
    "executive = bt_nav.cli:executive_main",
    "sim = bt_nav.cli:sim_main",
    "referee = bt_nav.cli:referee_main",
    "dump_tree = bt_nav.cli:dump_tree_main",
    "watch = bt_nav.cli:watch_main",
]

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
    entry_points={"console_scripts": ENTRY_POINTS},
)
