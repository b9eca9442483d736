"""The generated node's source: one student's ``reactive_navigator.py``, its knobs the constants at its top.

Kept as text (``string.Template``, ``$NAME`` fields) so the generated file is complete and standalone: it imports
nothing of bt_nav or of this package. Lines a mistake changes end in a ``# <mutation point>`` comment naming it
(:data:`tests.nodegen.mutate.MUTATIONS` replaces them).
"""

from __future__ import annotations

TEMPLATE = '''"""Lab 4 reactive_navigator, a generated right node (tests/nodegen, seed $SEED).

$DESCRIPTION.
$MISTAKE
"""

from __future__ import annotations

import math
import random
import sys

import rclpy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import LaserScan
from std_srvs.srv import SetBool

# CHOICE: $CHOICE

CHOICE = "$CHOICE"
EXECUTOR = "$EXECUTOR"  # single | multi
LOOP = "$LOOP"  # scan: decide and command in the scan callback; timer: in a control timer
TIMER_HZ = $TIMER_HZ
TIMING = "$TIMING"  # ros_time | scan_stamp | integrate | odom
TURN_RATE = $TURN_RATE  # rad/s
ANNOUNCE = $ANNOUNCE
FRONT_HALF = $FRONT_HALF  # deg
SIDE_CENTRE = $SIDE_CENTRE  # deg
SIDE_HALF = $SIDE_HALF  # deg
SIDE_STAT = "$SIDE_STAT"  # C compares the sides' min or mean
REARM_MARGIN = $REARM_MARGIN  # m: B re-arms once a side reads this far beyond safety_distance
PAUSE = $PAUSE  # s standing still between the trigger and the turn
C_TRIGGER = "$C_TRIGGER"  # sheet: front < 0.3 m; safety: front < safety_distance
SPIN = "$SPIN"  # B: clearer | left | right
PIVOT_DISTANCE = 0.3  # m, the sheet's C
CREEP = 0.05  # m/s, the template's
SETTLE = 0.5  # s standing after a turn, so the next one is a new maneuver
AEB = 0.22  # m: brake when the robot's own path is blocked this close (whatever the trigger's sector)
AEB_CLEAR = 0.45  # m: the brake's turn-away ends once the path is clear this far
PATH_HALF_WIDTH = 0.15  # m: the robot's half width and a margin
SLOW_ZONE = math.radians(20.0)  # odometry: slow down over the last 20 deg
MIN_RATE = 0.15  # rad/s: the slowest the odometry loop turns
NOMINAL_STEP = 1.0 / TIMER_HZ if LOOP == "timer" else 0.2  # s between two control steps, as planned


def index_for_angle(msg: LaserScan, angle_deg: float) -> int | None:
    """index = (theta - angle_min) / angle_increment, theta taken into the scan's sweep; None past its end."""
    offset = math.radians(angle_deg) - msg.angle_min  # <hardcoded_indices>
    if msg.angle_increment < 0.0:
        offset = -offset
    index = int(round((offset % (2.0 * math.pi)) / abs(msg.angle_increment)))
    return index if index < len(msg.ranges) else None


def usable(msg: LaserScan, r: float) -> bool:
    """A real return: not NaN, not inf, not the LDS-01's 0.0 (no return), within the LiDAR's range."""
    return math.isfinite(r) and max(msg.range_min, 0.01) <= r <= msg.range_max


def sector(msg: LaserScan, low_deg: float, high_deg: float, stat: str = "min") -> float:
    """The nearest (or mean) usable reading between two angles, beam by beam (inf: none usable)."""
    if not msg.ranges or not math.isfinite(msg.angle_increment) or msg.angle_increment == 0.0:
        return math.inf
    step = min(1.0, math.degrees(abs(msg.angle_increment)))
    values = []
    for k in range(int((high_deg - low_deg) / step) + 1):
        i = index_for_angle(msg, low_deg + k * step)
        if i is not None and usable(msg, msg.ranges[i]):
            values.append(msg.ranges[i])
    if not values:
        return math.inf
    return min(values) if stat == "min" else sum(values) / len(values)


def path_ahead(msg: LaserScan) -> float:
    """How far the robot's swept path is clear: a narrow front sector misses a corner its flank will touch."""
    ahead = math.inf
    for i, r in enumerate(msg.ranges):
        if usable(msg, r):
            angle = msg.angle_min + i * msg.angle_increment
            x, y = r * math.cos(angle), r * math.sin(angle)
            if x > 0.0 and abs(y) <= PATH_HALF_WIDTH:
                ahead = min(ahead, x)
    return ahead


class ReactiveNavigator(Node):
    """Stands until armed; creeps; turns in place when its choice's trigger holds; brakes before a wall."""

    def __init__(self) -> None:
        super().__init__("reactive_navigator")
        group = MutuallyExclusiveCallbackGroup()  # one callback at a time, whichever executor
        self.declare_parameter("safety_distance", 0.5)
        self.active = False  # <moves_before_toggle>
        self.state = "creep"  # creep | stand | turn | settle | brake
        self.until = 0.0
        self.sign, self.target, self.turned, self.began = 1.0, 0.0, 0.0, 0.0
        self.yaw: float | None = None
        self.last_yaw: float | None = None
        self.stamp = 0.0
        self.last_step: float | None = None
        self.elapsed = 0.0  # s since the previous control step
        self.period = 1.0 / TIMER_HZ if LOOP == "timer" else 0.2
        self.readings: dict[str, float] = {}
        self.rearmed = True
        self.publisher_ = self.create_publisher(Twist, "cmd_vel", 10)
        self.srv = self.create_service(SetBool, "toggle_navigation", self.toggle_callback, callback_group=group)
        self.create_subscription(LaserScan, "scan", self.scan_callback, qos_profile_sensor_data,
                                 callback_group=group)
        if TIMING == "odom":
            self.create_subscription(Odometry, "odom", self.odom_callback, 10, callback_group=group)
        if LOOP == "timer":
            self.create_timer(1.0 / TIMER_HZ, self.step, callback_group=group)  # ROS time (sim time in the grader)

    def clock(self) -> float:
        """Seconds on the clock this node times itself by: the last scan's stamp, or ROS time."""
        if TIMING == "scan_stamp":
            return self.stamp
        return self.get_clock().now().nanoseconds * 1e-9

    def distance(self) -> float:
        """The trigger distance: the parameter, read every time (a TA may set it at launch)."""
        return float(self.get_parameter("safety_distance").value)  # <ignores_safety_distance>

    def send(self, linear: float, angular: float) -> None:
        """One Twist on cmd_vel (the robot keeps the last one, so a stop must be sent)."""
        msg = Twist()
        msg.linear.x = float(linear)
        msg.angular.z = float(angular)
        self.publisher_.publish(msg)

    def toggle_callback(self, request: SetBool.Request, response: SetBool.Response) -> SetBool.Response:
        """Arm or disarm; a disarm stops the robot at once and drops any maneuver."""
        self.active = request.data  # <ignores_toggle_off>
        if not self.active:
            self.state = "creep"
            self.send(0.0, 0.0)
        response.success = True
        response.message = f"Navigation set to {self.active}"
        return response

    def odom_callback(self, msg: Odometry) -> None:
        """The yaw, the closed-loop turn's feedback."""
        q = msg.pose.pose.orientation
        self.yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))

    def scan_callback(self, msg: LaserScan) -> None:
        """Read the sectors (indices from angle_min and angle_increment); decide here on the scan loop."""
        self.stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        low, high = SIDE_CENTRE - SIDE_HALF, SIDE_CENTRE + SIDE_HALF
        self.readings = {
            "front": sector(msg, -FRONT_HALF, FRONT_HALF), "left": sector(msg, low, high),
            "right": sector(msg, -high, -low), "left_cmp": sector(msg, low, high, SIDE_STAT),
            "right_cmp": sector(msg, -high, -low, SIDE_STAT), "ahead": path_ahead(msg)}
        if LOOP == "scan":
            self.step()

    def step(self) -> None:
        """One control step: go on with the turn, stand out a pause, or decide afresh."""
        if not self.active or not self.readings:
            return
        now = self.clock()
        self.elapsed = now - self.last_step if self.last_step is not None else 0.0
        if 0.0 < self.elapsed < 1.0:
            self.period = self.elapsed
        self.last_step = now
        if self.state == "turn":
            self.advance_turn(now)
        elif self.state in ("stand", "settle", "brake") and now < self.until:
            self.send(0.0, 0.0)
        elif self.state == "stand":
            self.start_turn(now)
        elif self.state == "brake":
            self.recover()
        else:
            self.state = "creep"
            self.decide(now)

    def decide(self, now: float) -> None:
        """The sheet's logic flow: the trigger starts the maneuver, else creep (braking first on a blocked path)."""
        r, sd = self.readings, self.distance()
        squeezed = r["left"] < sd and r["right"] < sd  # <left_or_right>
        if not (r["left"] < sd + REARM_MARGIN and r["right"] < sd + REARM_MARGIN):
            self.rearmed = True
        pivot = PIVOT_DISTANCE if C_TRIGGER == "sheet" else sd
        trigger = {"A": r["front"] < sd, "B": squeezed and self.rearmed, "C": r["front"] < pivot}[CHOICE]
        if trigger:
            self.execute_rotation_maneuver(now)
        elif r["ahead"] < AEB:
            self.state, self.until = "brake", now + 1.0
            self.send(0.0, 0.0)
            self.get_logger().warn(f"AEB: path blocked at {r['ahead']:.2f} m, braking")
        else:
            self.drive_forward()

    def execute_rotation_maneuver(self, now: float) -> None:
        """Choose the side and the angle now; stand PAUSE s first, then turn."""
        r = self.readings
        clearer = 1.0 if r["left_cmp"] >= r["right_cmp"] else -1.0
        if CHOICE == "A":
            sign, angle = random.choice((1.0, -1.0)), random.uniform(90.0, 180.0)
        elif CHOICE == "B":
            self.rearmed = False
            sign, angle = {"clearer": clearer, "left": 1.0, "right": -1.0}[SPIN], 180.0
        else:
            sign, angle = clearer, 90.0  # <wrong_side>
        self.sign, self.target = sign, math.radians(angle)  # <angle_45>
        if ANNOUNCE:
            self.get_logger().info(f"Obstacle Detected! Executing rotation maneuver {CHOICE}: "
                                   f"{math.degrees(self.target):.0f} deg {'left' if sign > 0 else 'right'}")
        if PAUSE > 0.0:
            self.state, self.until = "stand", now + PAUSE
            self.send(0.0, 0.0)
        else:
            self.start_turn(now)

    def start_turn(self, now: float) -> None:
        """The rotation begins: the clocks and the odometry count from here."""
        self.state, self.began, self.turned, self.last_yaw = "turn", now, 0.0, self.yaw
        self.turn_command(TURN_RATE)

    def advance_turn(self, now: float) -> None:
        """Turn on until the angle is done: by odometry, or open loop, ending on the step nearest the end."""
        rate = TURN_RATE
        if TIMING == "odom":
            if self.yaw is not None and self.last_yaw is not None:
                self.turned += abs(math.remainder(self.yaw - self.last_yaw, 2.0 * math.pi))
            self.last_yaw = self.yaw
            left = self.target - self.turned
            done = left <= math.radians(1.0)
            rate = TURN_RATE if left > SLOW_ZONE else max(MIN_RATE, TURN_RATE * left / SLOW_ZONE)
        else:
            if TIMING == "integrate":  # every second since the last step, however late it came
                self.turned += TURN_RATE * max(self.elapsed, 0.0)
            else:
                self.turned = TURN_RATE * (now - self.began)
            # end on the step nearest the end: half a step early at most (the nominal step: one late step must not
            # end the turn early)
            done = self.turned + 0.5 * TURN_RATE * min(self.period, NOMINAL_STEP) >= self.target
        if done:
            self.end_turn(now)
        else:
            self.turn_command(rate)

    def turn_command(self, rate: float) -> None:
        """A turning command: in place, no forward motion during the maneuver."""
        self.send(0.0, self.sign * rate)  # <forward_while_turning>

    def end_turn(self, now: float) -> None:
        """Stop, and stand SETTLE s before deciding again."""
        self.state, self.until = "settle", now + SETTLE
        self.send(0.0, 0.0)
        if ANNOUNCE:
            self.get_logger().info("Rotation maneuver done")

    def recover(self) -> None:
        """The AEB's way out after standing 1 s: turn in place towards the clearer side until the path is clear.

        C pivots instead: its brake stopped it short of the pivot distance (a wall slanting across the path blocks
        the robot's flank before a narrow front reads 0.3 m), and an obstacle in front is what C pivots from."""
        r = self.readings
        if CHOICE == "C":
            self.execute_rotation_maneuver(self.clock())
            return
        if r["ahead"] > AEB_CLEAR:
            self.state = "creep"
            self.send(0.0, 0.0)
            return
        self.send(0.0, min(TURN_RATE, 0.6) * (1.0 if r["left"] >= r["right"] else -1.0))

    def drive_forward(self) -> None:
        """The template's creep."""
        self.send(CREEP, 0.0)  # <never_creeps>


def main() -> None:
    """Spin until Ctrl-C; then a last zero twist (rclpy's own signal handler would close the context first)."""
    rclpy.init(args=sys.argv, signal_handler_options=SignalHandlerOptions.NO)
    node = ReactiveNavigator()
    executor = MultiThreadedExecutor(num_threads=2) if EXECUTOR == "multi" else SingleThreadedExecutor()
    executor.add_node(node)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if rclpy.ok():
            node.send(0.0, 0.0)
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
'''
