#!/usr/bin/python3
"""package.xml against what the package uses, both ways, for the ROS packages among them.

Uses: the C++ includes (`#include <pkg/...>`) and the catkin components of CMakeLists.txt; the
Python imports (`import pkg`, `from pkg.msg import`); the launch files' `pkg="..."` and
`$(find ...)`. Code under src/, include/, launch/, config/, rviz/ and the installed scripts
(catkin_install_python) is the package's; test/ is the tests'. A name is a ROS package when
rospack knows it (Debian's eigen, OpenCV, yaml-cpp, TBB and python3-* are not checked here).

- every ROS package the package's code uses is a <depend> (or build_depend + exec_depend);
- every ROS package only the tests use is a <test_depend> (or a depend for another reason);
- every declared ROS package is used somewhere (catkin_package's message_generation and
  message_runtime and the drivers left out on purpose are the exceptions listed below);
- every catkin component of find_package is used by the package's code, and declared.
Run by rostest (package_deps.test) for the ROS environment.
"""
import os
import re
import sys
import unittest
import xml.etree.ElementTree as ElementTree

import rospkg
import rostest

ROOT = os.path.realpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
# Used without a name in the code: the message generators (add_message_files), the build tool.
IMPLICIT = {"catkin", "message_generation", "message_runtime", "rostest", "roslaunch"}
# Included by launch files only behind start_driver / start_ekf, because Debian does not package
# them: not declared (rosdep could not install them), and said so in the launch files.
OPTIONAL = {"openni2_launch", "realsense2_camera", "freenect_launch", "robot_localization"}
# Header folders named otherwise than their package.
HEADERS = {"ros": "roscpp"}
# Declared system dependencies (rosdep keys) and the header folder or module that uses them.
SYSTEM = {"eigen": "Eigen", "libopencv-dev": "opencv2", "yaml-cpp": "yaml-cpp", "tbb": "tbb",
          "python3-opencv": "cv2", "python3-yaml": "yaml", "python3-numpy": "numpy",
          "python3-matplotlib": "matplotlib", "gtest": "gtest", "libcli11-dev": "CLI",
          "libpcl-all-dev": "pcl"}
# catkin components the code uses without including a header of their own.
INDIRECT = {"tf2": "tf2:: functions and libtf2 through tf2_eigen's and tf2_ros' headers"}
INSTALLED_SCRIPTS = ["scripts/tum_to_bag", "scripts/record_trajectory",
                     "scripts/plot_trajectories.py"]


def files(*tops, suffixes=()):
    for top in tops:
        path = os.path.join(ROOT, top)
        if os.path.isfile(path):
            yield path
            continue
        for folder, _, names in os.walk(path):
            for name in names:
                if not suffixes or name.endswith(suffixes):
                    yield os.path.join(folder, name)


def uses(paths):
    """Names of packages the files use: C++ includes, Python imports, launch references."""
    names = set()
    for path in paths:
        with open(path, errors="replace") as f:
            text = f.read()
        names.update(HEADERS.get(n, n) for n in re.findall(r"#include\s*<([A-Za-z0-9_-]+)[/.>]",
                                                            text))
        names.update(re.findall(r"^\s*(?:from|import)\s+([A-Za-z0-9_]+)", text, re.M))
        names.update(re.findall(r'pkg="([A-Za-z0-9_]+)"', text))
        names.update(re.findall(r"\$\(find ([A-Za-z0-9_]+)\)", text))
    return names


class PackageDepsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.rospack = rospkg.RosPack()
        tree = ElementTree.parse(os.path.join(ROOT, "package.xml"))
        cls.declared = {}
        for element in tree.getroot():
            if element.tag.endswith("depend"):
                cls.declared.setdefault(element.tag, set()).add(element.text.strip())
        depend = cls.declared.get("depend", set())
        cls.build_deps = depend | cls.declared.get("build_depend", set())
        cls.run_deps = depend | cls.declared.get("exec_depend", set())
        cls.declared_test = cls.declared.get("test_depend", set())
        with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
            cmake = f.read()
        components = re.search(r"find_package\(catkin REQUIRED COMPONENTS(.*?)\)", cmake, re.S)
        cls.components = set(components.group(1).split())
        code = list(files("src", "include", suffixes=(".cpp", ".hpp", ".h")))
        launch = list(files("launch", suffixes=(".launch",)))
        scripts = list(files(*INSTALLED_SCRIPTS))
        cls.all_names = uses(code + launch + list(files("scripts", "test")))
        cls.code_uses = cls.ros(uses(code))
        cls.run_uses = cls.ros(uses(launch + scripts))
        cls.tests_use = cls.ros(uses(files("test", suffixes=(".cpp", ".hpp", ".py", ".test",
                                                             ".launch"))))

    @classmethod
    def ros(cls, names):
        known = set()
        for name in names:
            if name == "acvo":
                continue
            try:
                cls.rospack.get_path(name)
                known.add(name)
            except rospkg.ResourceNotFound:
                pass
        return known

    def test_every_catkin_component_is_used_by_the_code_and_declared(self):
        unused = sorted(self.components - self.code_uses - IMPLICIT - set(INDIRECT))
        self.assertEqual(unused, [], "find_package(catkin COMPONENTS) that src/ and include/ "
                                     "do not use")
        self.assertEqual(sorted(self.components - self.build_deps - IMPLICIT), [],
                         "catkin components not declared")

    def test_what_the_code_uses_is_declared(self):
        missing = sorted(self.code_uses - self.build_deps - IMPLICIT)
        self.assertEqual(missing, [], "used by src/, include/ or CMakeLists.txt, not a depend "
                                      "or build_depend")
        missing = sorted((self.code_uses | self.run_uses) - self.run_deps - IMPLICIT - OPTIONAL)
        self.assertEqual(missing, [], "used at run time, not a depend or exec_depend")

    def test_what_only_the_tests_use_is_a_test_depend(self):
        missing = sorted(self.tests_use - self.build_deps - self.run_deps - self.declared_test - IMPLICIT - OPTIONAL)
        self.assertEqual(missing, [], "used by test/, not declared")
        misplaced = sorted((self.build_deps | self.run_deps) & (self.tests_use - self.code_uses -
                                                      self.run_uses) - IMPLICIT)
        self.assertEqual(misplaced, [], "used by the tests only, declared for the package")

    def test_every_declared_ros_package_is_used(self):
        declared = self.ros(self.build_deps | self.run_deps | self.declared_test) - IMPLICIT
        used = self.code_uses | self.run_uses | self.tests_use | set(INDIRECT)
        self.assertEqual(sorted(declared - used), [], "declared, used nowhere")
        self.assertEqual(sorted(self.ros(self.declared_test) & self.code_uses), [],
                         "a test_depend used by the package's code")

    def test_every_declared_system_dependency_is_used(self):
        declared = self.build_deps | self.run_deps | self.declared_test
        for name in sorted(declared - IMPLICIT):
            if self.ros({name}):
                continue  # checked above
            self.assertIn(name, SYSTEM, "declared '%s' is neither a ROS package here nor a "
                                        "system dependency of the table" % name)
            self.assertIn(SYSTEM[name], self.all_names, "declared '%s', used nowhere" % name)

    def test_the_drivers_left_out_are_not_declared(self):
        self.assertEqual(sorted(OPTIONAL & (self.build_deps | self.run_deps | self.declared_test)), [])


if __name__ == "__main__":
    rostest.rosrun("acvo", "package_deps", PackageDepsTest, sys.argv)
