"""Server messages: byte-exact golden lines and round trips (protocol.md §6, §18)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usarsim import readings as r
from usarsim.errors import ProtocolError
from usarsim.protocol import messages as m
from usarsim.protocol.grammar import Segment
from usarsim.protocol.messages import format_message, format_reading, parse_message


def _sta(time: float, vehicle_type: str = "GroundVehicle", **status) -> m.StatusMessage:
    """A STA message: its time and the robot's status (RobotStatus, the payload)."""
    return m.StatusMessage(time, r.RobotStatus(vehicle_type, **status))


SCAN_RANGES = (11.3059, 11.3133, 0.25, 20.0)

GOLDEN = [
    # §6.1
    (
        m.GameInfo(level="DM-USAR_yellow"),
        "NFO {Gametype BotDeathMatch} {Level DM-USAR_yellow} {TimeLimit 0}",
    ),
    (
        m.GameInfo(gametype="BotDeathMatch", level="DM-Factory_250", time_limit=20),
        "NFO {Gametype BotDeathMatch} {Level DM-Factory_250} {TimeLimit 20}",
    ),
    (
        m.StartPoses(
            poses=(
                m.StartPose(name="PlayerStart1", location=(4.5, 1.9, 1.8), rotation=(0.0, 0.0, 0.0)),
                m.StartPose(name="PlayerStart2", location=(10.24, 3.54, 10.05), rotation=(0.0, 0.0, 1.57)),
            )
        ),
        "NFO {StartPoses 2} {PlayerStart1 4.50,1.90,1.80 0.00,0.00,0.00 PlayerStart2 10.24,3.54,10.05 0.00,0.00,1.57}",
    ),
    (m.StartPoses(poses=()), "NFO {StartPoses 0}"),
    (
        m.StartPoses(
            poses=(m.StartPose(name="BlueGoal", location=(-2.55, -0.001, -0.19), rotation=(0, -0.03, -0.01)),)
        ),
        "NFO {StartPoses 1} {BlueGoal -2.55,0.00,-0.19 0.00,-0.03,-0.01}",
    ),
    (
        m.PathNodes(nodes=(m.StartPose(name="PN1", location=(1, 2, 3), rotation=(0, 0, 0)),)),
        "NFO {PathNodes 1} {PN1 1.00,2.00,3.00 0.00,0.00,0.00}",
    ),
    (m.PathNodes(), "NFO {PathNodes 0}"),
    (
        m.ClosestPathNode(name="PN1", location=(1.0, -2.5, 0.0)),
        "NFO {Pathnode PN1} {Location 1.00,-2.50,0.00}",
    ),
    # §6.2
    (
        _sta(31.2, battery_s=1200),
        "STA {Type GroundVehicle} {Time 31.20} {FrontSteer 0.0000} {RearSteer 0.0000} "
        "{LightToggle False} {LightIntensity 0} {Battery 1200} {View -1}",
    ),
    (
        _sta(5609.45, battery_s=1199, view=0, light_toggle=True, light_intensity=100),
        "STA {Type GroundVehicle} {Time 5609.45} {FrontSteer 0.0000} {RearSteer 0.0000} "
        "{LightToggle True} {LightIntensity 100} {Battery 1199} {View 0}",
    ),
    (
        _sta(
            120.3,
            joints=(
                ("FRFlipper", -0.0006),
                ("FLFlipper", -0.0006),
                ("RRFlipper", 0.0012),
                ("RLFlipper", 0.0012),
            ),
            battery_s=1187,
        ),
        "STA {Type GroundVehicle} {Time 120.30} {FrontSteer 0.0000} {RearSteer 0.0000} "
        "{FRFlipper -0.0006} {FLFlipper -0.0006} {RRFlipper 0.0012} {RLFlipper 0.0012} "
        "{LightToggle False} {LightIntensity 0} {Battery 1187} {View -1}",
    ),
    (
        _sta(3.2, front_steer=0.5236, rear_steer=-0.5236, battery_s=3600, vehicle_type="LeggedRobot"),
        "STA {Type LeggedRobot} {Time 3.20} {FrontSteer 0.5236} {RearSteer -0.5236} "
        "{LightToggle False} {LightIntensity 0} {Battery 3600} {View -1}",
    ),
    (
        _sta(268.5, battery_s=1192, vehicle_type="AerialVehicle"),
        "STA {Type AerialVehicle} {Time 268.50} {LightToggle False} {LightIntensity 0} {Battery 1192} {View -1}",
    ),
    # §6.3
    (
        m.SensorMessage(
            time=5608.85,
            reading=r.RangeReading(
                sensor_type="Sonar",
                items=(r.RangeItem(name="F1", range_m=2.5098), r.RangeItem(name="F2", range_m=3.3153)),
            ),
        ),
        "SEN {Time 5608.8500} {Type Sonar} {Name F1 Range 2.5098} {Name F2 Range 3.3153}",
    ),
    (
        m.SensorMessage(
            time=1.5, reading=r.RangeReading(sensor_type="IR", items=(r.RangeItem(name="IR1", range_m=0.85),))
        ),
        "SEN {Time 1.5000} {Type IR} {Name IR1 Range 0.8500}",
    ),
    (
        m.SensorMessage(
            time=5608.85,
            reading=r.RangeScanReading(
                sensor_type="RangeScanner",
                name="Scanner1",
                resolution_rad=math.radians(1.0),
                fov_rad=math.pi,
                ranges_m=SCAN_RANGES,
            ),
        ),
        "SEN {Time 5608.8500} {Type RangeScanner} {Name Scanner1} {Resolution 0.0174} "
        "{FOV 3.1415} {Range 11.3059,11.3133,0.2500,20.0000}",
    ),
    (
        m.SensorMessage(
            time=2.0,
            reading=r.RangeScan3DReading(
                name="Scanner",
                resolution_rad=(0.0174, math.radians(1.0)),
                fov_rad=(0.5, math.pi),
                ranges_m=(1.0, 2.0, 3.5),
            ),
        ),
        "SEN {Time 2.0000} {Type RangeScanner3D} {Name Scanner} {Resolution 0.0174,0.0174} "
        "{FOV 0.5000,3.1415} {Range 1.0000,2.0000,3.5000}",
    ),
    (  # one frame (line) of a depth picture of 2 x 4 pixels in 2 frames (protocol.md 6.3)
        m.SensorMessage(
            time=3.5,
            reading=r.RangeImageReading(
                name="KinectDepth",
                pixels=(2, 4),
                fov_rad=(1.0122, 0.7854),
                ranges_m=(1.838, 4.0, 0.8, 2.25),
                frames=2,
                frame=1,
            ),
        ),
        "SEN {Time 3.5000} {Type RangeImager} {Name KinectDepth} {Frames 2} {Frame 1} {Resolution 2,4} "
        "{FOV 1.0122,0.7854} {Range 1.838,4.000,0.800,2.250}",
    ),
    (
        m.SensorMessage(
            time=44.5467,
            reading=r.OdometryReading(name="Odometry", x_m=0.2514, y_m=-0.0051, theta_rad=6.2432),
        ),
        "SEN {Time 44.5467} {Type Odometry} {Name Odometry} {Pose 0.2514,-0.0051,6.2432}",
    ),
    (
        m.SensorMessage(
            time=7.0,
            reading=r.EncoderReading(
                items=(r.EncoderItem(name="ECLeft", tick=-331), r.EncoderItem(name="ECRight", tick=-4))
            ),
        ),
        "SEN {Time 7.0000} {Type Encoder} {Name ECLeft Tick -331} {Name ECRight Tick -4}",
    ),
    (
        m.SensorMessage(
            time=5608.85,
            reading=r.PoseReading(
                sensor_type="GroundTruth",
                name="GroundTruth",
                location=(12.61, -2.68, 1.64),
                orientation=(0.0, 6.23, -1e-12),
            ),
        ),
        "SEN {Time 5608.8500} {Type GroundTruth} {Name GroundTruth} {Location 12.6100,-2.6800,1.6400} "
        "{Orientation 0.0000,6.2300,0.0000}",
    ),
    (
        m.SensorMessage(
            time=None,
            reading=r.PoseReading(
                sensor_type="INS",
                name="INS",
                location=(1.23, 0.45, 0.02),
                orientation=(0.01, -0.0132, 1.57),
            ),
        ),
        "SEN {Type INS} {Name INS} {Location 1.2300,0.4500,0.0200} {Orientation 0.0100,6.2700,1.5700}",
    ),
    (
        m.SensorMessage(time=3.0, reading=r.OrientationReading(name="INU", orientation=(0.1, 0.2, -0.3))),
        "SEN {Time 3.0000} {Type INU} {Name INU} {Orientation 0.1000,0.2000,5.9832}",
    ),
    (
        m.SensorMessage(time=3.0, reading=r.TouchReading(items=(r.TouchItem(name="Touch", touching=False),))),
        "SEN {Time 3.0000} {Type Touch} {Name Touch Touch False}",
    ),
    (
        m.SensorMessage(
            time=3.0,
            reading=r.GpsReading(
                name="GPS", fix=True, satellites=11, latitude=(39, 8.0341, "N"), longitude=(77, 13.0001, "W")
            ),
        ),
        "SEN {Time 3.0000} {Type GPS} {Name GPS} {Latitude 39,8.0341,N} {Longitude 77,13.0001,W} "
        "{Fix 1} {Satellites 11}",
    ),
    (
        m.SensorMessage(time=3.0, reading=r.GpsReading(name="GPS", fix=False, satellites=2)),
        "SEN {Time 3.0000} {Type GPS} {Name GPS} {Fix 0} {Satellites 2}",
    ),
    (
        m.SensorMessage(time=7.5, reading=r.SoundReading(name="Mic", loudness_db=42.5, duration_s=1.0)),
        "SEN {Time 7.5000} {Type Sound} {Name Mic} {Loudness 42.5000} {Duration 1.0000}",
    ),
    (
        m.SensorMessage(time=7.5, reading=r.HumanMotionReading(name="HM", probability=0.25)),
        "SEN {Time 7.5000} {Type HumanMotion} {Name HM} {Prob 0.2500}",
    ),
    (
        m.SensorMessage(
            time=3.0,
            reading=r.TachometerReading(name="TachTest", velocities_rad_s=(1.2, 1.2), positions_rad=(3.4, 3.1)),
        ),
        "SEN {Time 3.0000} {Type Tachometer} {Name TachTest} {Vel 1.2000,1.2000} {Pos 3.4000,3.1000}",
    ),
    (
        m.SensorMessage(
            time=3.0,
            reading=r.ImuReading(
                name="IMU",
                acceleration=(0.1, 0.0, -9.81),
                angular_velocity=(0.0, 0.0, 0.5),
                angular_acceleration=(0.0, 0.0, 0.0),
                orientation=(0.0, 0.0, -1.5708),
            ),
        ),
        "SEN {Time 3.0000} {Type IMU} {Name IMU} {XYZAcceleration 0.1000,0.0000,-9.8100} "
        "{AngularVel 0.0000,0.0000,0.5000} {AngularAccel 0.0000,0.0000,0.0000} "
        "{Rotation 0.0000,0.0000,-1.5708}",
    ),
    (
        m.SensorMessage(
            time=3.0,
            reading=r.VictimReading(
                name="VictSensor",
                parts=(
                    r.VictimPart(part_name="Head", location=(2.51, 0.34, -0.2)),
                    r.VictimPart(part_name="Chest", location=(2.6, 0.3, 0.05)),
                ),
            ),
        ),
        "SEN {Time 3.0000} {Type VictSensor} {Name VictSensor} {PartName Head} "
        "{Location 2.5100,0.3400,-0.2000} {PartName Chest} {Location 2.6000,0.3000,0.0500}",
    ),
    (
        m.SensorMessage(time=3.0, reading=r.VictimReading(name="VictSensor", parts=())),
        "SEN {Time 3.0000} {Type VictSensor} {Status NoVictims}",
    ),
    (
        m.SensorMessage(
            time=3.0,
            reading=r.RfidReading(
                name="RFID",
                tags=(
                    r.RfidTag(tag_id=11137, location=(3.04, 4.52, 0.23), memory="victim is here"),
                    r.RfidTag(tag_id=11138, location=(1.02, -0.8, 0.23)),
                ),
            ),
        ),
        "SEN {Time 3.0000} {Type RFID} {Name RFID} {ID 11137} {Location 3.0400,4.5200,0.2300} "
        "{Mem victim is here} {ID 11138} {Location 1.0200,-0.8000,0.2300}",
    ),
    (
        m.SensorMessage(time=3.0, reading=r.RfidReading(name="RFID", tags=())),
        "SEN {Time 3.0000} {Type RFID} {Name RFID}",
    ),
    # §6.8 GEO
    (
        m.RobotGeometry(
            class_name="P2AT",
            dimensions=(0.5238, 0.4968, 0.2913),
            cog=(0.0, 0.0, 0.0),
            wheel_radius=0.13,
            wheel_separation=0.4712,
            wheel_base=0.2884,
        ),
        "GEO {Type GroundVehicle} {Name P2AT} {Dimensions 0.5238,0.4968,0.2913} "
        "{COG 0.0000,0.0000,0.0000} {WheelRadius 0.1300} {WheelSeparation 0.4712} {WheelBase 0.2884}",
    ),
    (
        m.RobotGeometry(vehicle_type="AerialVehicle", class_name="AirRobot", dimensions=(1.0, 1.0, 0.2)),
        "GEO {Type AerialVehicle} {Name AirRobot} {Dimensions 1.0000,1.0000,0.2000} {COG 0.0000,0.0000,0.0000}",
    ),
    (
        m.ItemGeometry(
            item_type="Sonar",
            items=(
                m.ItemPose(name="F1", location=(0.145, -0.13, 0.0), orientation=(0.0, 0.0, -1.5708)),
                m.ItemPose(name="F2", location=(0.185, -0.115, 0.0), orientation=(0.0, 0.0, -0.8727)),
            ),
        ),
        "GEO {Type Sonar} {Name F1 Location 0.1450,-0.1300,0.0000 Orientation 0.0000,0.0000,-1.5708 "
        "Mount HARD} {Name F2 Location 0.1850,-0.1150,0.0000 Orientation 0.0000,0.0000,-0.8727 Mount HARD}",
    ),
    (
        m.ItemGeometry(
            item_type="Camera",
            items=(
                m.ItemPose(
                    name="Camera",
                    location=(0.082, 0.0002, 0.0613),
                    orientation=(0.0, 0.0, 0.0),
                    mount="CameraTilt",
                ),
            ),
        ),
        "GEO {Type Camera} {Name Camera Location 0.0820,0.0002,0.0613 Orientation 0.0000,0.0000,0.0000 "
        "Mount CameraTilt}",
    ),
    (m.ItemGeometry(item_type="Sonar"), "GEO {Type Sonar}"),
    (m.EmptyGeometry(item_type="Gripper"), "GEO {Type Gripper}"),
    (m.EmptyGeometry(item_type="Camera", name="Cam9"), "GEO {Type Camera} {Name Cam9}"),
    (
        m.MisPkgGeometry(
            packages=(
                m.PackageGeometry(
                    name="CameraPanTilt",
                    links=(
                        m.LinkGeometry(
                            link=1, parent_link=-1, location=(0.1239, 0.0, -0.2036), orientation=(math.pi, 0, 0)
                        ),
                        m.LinkGeometry(
                            link=2, parent_link=1, location=(0.0, 0.0, 0.0599), orientation=(math.pi / 2, 0, 0)
                        ),
                    ),
                ),
            )
        ),
        "GEO {Type MisPkg} {Name CameraPanTilt} {Link 1} {ParentLink -1} {Location 0.1239,0.0000,-0.2036} "
        "{Orientation 3.1415,0.0000,0.0000} {Link 2} {ParentLink 1} {Location 0.0000,0.0000,0.0599} "
        "{Orientation 1.5707,0.0000,0.0000}",
    ),
    # §6.7 CONF
    (
        m.RobotConfiguration(
            class_name="P2AT",
            steering_type="SkidSteered",
            mass_kg=14.0,
            max_speed=5.385,
            max_torque=60.0,
            max_front_steer=0.0,
            max_rear_steer=0.0,
        ),
        "CONF {Type GroundVehicle} {Name P2AT} {SteeringType SkidSteered} {Mass 14.0000} "
        "{MaxSpeed 5.3850} {MaxTorque 60.0000} {MaxFrontSteer 0.0000} {MaxRearSteer 0.0000}",
    ),
    (
        m.ItemConfiguration(
            item_type="Sonar",
            items=(
                m.ItemConf(name="F1", fields=(("MaxRange", "5.0000"), ("MinRange", "0.1000"), ("BeamAngle", "0.3491"))),
                m.ItemConf(name="F2", fields=(("MaxRange", "5.0000"), ("MinRange", "0.1000"), ("BeamAngle", "0.3491"))),
            ),
        ),
        "CONF {Type Sonar} {Name F1} {MaxRange 5.0000} {MinRange 0.1000} {BeamAngle 0.3491} "
        "{Name F2} {MaxRange 5.0000} {MinRange 0.1000} {BeamAngle 0.3491}",
    ),
    (
        m.ItemConfiguration(
            item_type="RangeScanner",
            items=(
                m.ItemConf(
                    name="Scanner1",
                    fields=(
                        ("MaxRange", "20.0000"),
                        ("MinRange", "0.1000"),
                        ("Resolution", "0.0174"),
                        ("Fov", "3.1415"),
                        ("Paning", "True"),
                        ("Tilting", "False"),
                    ),
                ),
            ),
        ),
        "CONF {Type RangeScanner} {Name Scanner1} {MaxRange 20.0000} {MinRange 0.1000} "
        "{Resolution 0.0174} {Fov 3.1415} {Paning True} {Tilting False}",
    ),
    (m.EmptyConfiguration(item_type="Gripper"), "CONF {Type Gripper}"),
    (m.EmptyConfiguration(item_type="Gripper", name="Gripper"), "CONF {Type Gripper} {Name Gripper}"),
    (
        m.MisPkgConfiguration(
            packages=(
                m.PackageConfiguration(
                    name="CameraPanTilt",
                    links=(
                        m.LinkConfiguration(
                            link=1, joint_type="Revolute", max_speed=0.17, max_torque=20.0, min_range=1.0, max_range=0.0
                        ),
                        m.LinkConfiguration(
                            link=2,
                            joint_type="Revolute",
                            max_speed=0.17,
                            max_torque=20.0,
                            min_range=-0.16,
                            max_range=0.4,
                        ),
                    ),
                ),
            )
        ),
        "CONF {Type MisPkg} {Name CameraPanTilt} {Link 1} {JointType Revolute} {MaxSpeed 0.1700} "
        "{MaxTorque 20.0000} {MinRange 1.0000} {MaxRange 0.0000} {Link 2} {JointType Revolute} "
        "{MaxSpeed 0.1700} {MaxTorque 20.0000} {MinRange -0.1600} {MaxRange 0.4000}",
    ),
    # §6.4
    (
        m.MisPkgMessage(
            102.09,
            r.PackageState(
                "CameraPanTilt",
                (
                    r.PackageLink(link=1, value=0.0, torque=-20.0),
                    r.PackageLink(link=2, value=-0.16, torque=-20.0),
                ),
            ),
        ),
        "MISSTA {Time 102.09} {Name CameraPanTilt} {Link 1} {Value 0.0000} {Torque -20.0000} "
        "{Link 2} {Value -0.1600} {Torque -20.0000}",
    ),
    # §6.5 / §5.4
    (
        m.Result(time=31.6, item_type="RFIDReleaser", name="Gun"),
        "RES {Time 31.60} {Type RFIDReleaser} {Name Gun} {Status OK}",
    ),
    (
        m.Result(time=31.6, item_type="RFIDReleaser", name="Gun", status="Failed"),
        "RES {Time 31.60} {Type RFIDReleaser} {Name Gun} {Status Failed}",
    ),
    (
        m.Result(time=2.0, item_type="RFID", name="RFID", extra=(("ID", "11137"), ("Mem", "hello world"))),
        "RES {Time 2.00} {Type RFID} {Name RFID} {Status OK} {ID 11137} {Mem hello world}",
    ),
    (
        m.Result(time=2.0, item_type="Odometry", name=None),
        "RES {Time 2.00} {Type Odometry} {Status OK}",
    ),
    (
        m.CameraZoomResult(time=5.0, cameras=(m.CameraZoom(name="Camera", fov=0.87, status="OK"),)),
        "RES {Time 5.00} {Type Camera} {Name Camera} {FOV 0.8700} {Status OK}",
    ),
    (
        m.ViewportsResult(
            time=5.0,
            config="SingleView",
            viewports=(
                m.ViewportState(index=1, camera="Camera"),
                m.ViewportState(index=2, camera="Disabled"),
                m.ViewportState(index=3, camera="None", status="Failed"),
                m.ViewportState(index=4, camera="Disabled"),
            ),
        ),
        "RES {Time 5.00} {Type Viewports} {Config SingleView} {Status OK} {Viewport1 Camera} "
        "{Status OK} {Viewport2 Disabled} {Status OK} {Viewport3 None} {Status Failed} "
        "{Viewport4 Disabled} {Status OK}",
    ),
    # §6.6
    (
        m.EffecterStatus(time=20.1, effecter_type="Gripper", name="Gripper1", status="OPEN"),
        "EFF {Time 20.1000} {Type Gripper} {Name Gripper1} {Status OPEN}",
    ),
    (
        m.EffecterStatus(
            time=1.0,
            effecter_type="ToolChanger",
            name="tc",
            status="CLOSED",
            extra=(("ToolType", "Gripper"), ("Tool", "KR60gripper")),
        ),
        "EFF {Time 1.0000} {Type ToolChanger} {Name tc} {Status CLOSED} {ToolType Gripper} {Tool KR60gripper}",
    ),
    (
        m.EffecterStatus(time=1.0, effecter_type="Vacuum", name="v", extra=(("On", ""),)),
        "EFF {Time 1.0000} {Type Vacuum} {Name v} {On}",
    ),
    # §6.9, §18
    (m.Die(killer="World", damage_type="Fell"), "DIE {Killer World} {DamageType Fell}"),
    (m.Stepped(time=12.34), "STEPPED {Time 12.3400}"),
    (m.Pong(id="7", time=1.5), "PONG {Id 7} {Time 1.5000}"),
    (m.Pong(), "PONG"),
    (
        m.error_reply("init", "unknown start pose 'Nowhere' {known: PlayerStart1}\r\n"),
        "ERROR {Command INIT} {Reason unknown start pose 'Nowhere' (known: PlayerStart1)}",
    ),
    (
        m.UnknownMessage(type="ACTSTA", segments=(Segment("Time", "1.00"), Segment("Name", "arm"))),
        "ACTSTA {Time 1.00} {Name arm}",
    ),
    # UDK actuator API (§5.8, §6.4, §6.7, §6.8)
    (
        m.ActuatorStatus(
            time=1.5, name="arm", links=(r.PackageLink(1, 0.5, -2.0), r.PackageLink(2, -0.25, 0.0)), gripper=1
        ),
        "ASTA {Time 1.5000} {Name arm} {Link 1} {Value 0.5000} {Torque -2.0000} {Link 2} {Value -0.2500} "
        "{Torque 0.0000} {Gripper 1}",
    ),
    (
        m.ActuatorConfiguration(
            actuators=(
                m.ActuatorConfig(
                    "arm",
                    (
                        m.ActuatorLinkConfiguration(1, "Revolute", 50.0, -1.5, 1.5),
                        m.ActuatorLinkConfiguration(2, "Prismatic", 20.0, 0.0, 0.3),
                    ),
                ),
                m.ActuatorConfig("pt", ()),
            )
        ),
        "CONF {Type Actuator} {Name arm} {Link 1} {JointType Revolute} {MaxTorque 50.0000} {MinValue -1.5000} "
        "{MaxValue 1.5000} {Link 2} {JointType Prismatic} {MaxTorque 20.0000} {MinValue 0.0000} {MaxValue 0.3000} "
        "{Name pt}",
    ),
    (
        m.ActuatorGeometry(
            actuators=(
                m.ActuatorPose(
                    "arm",
                    (0.1, 0.0, -0.2),
                    (0.0, 0.0, 3.1416),
                    "P3AT",
                    (
                        m.ActuatorLinkGeometry(1, -1, (0.0, 0.0, 0.1), (0.0, 0.0, 0.0)),
                        m.ActuatorLinkGeometry(2, 0, (0.3, 0.0, 0.0), (0.0, 1.5708, 0.0)),
                    ),
                ),
            )
        ),
        "GEO {Type Actuator} {Name arm} {Location 0.1000,0.0000,-0.2000} {Orientation 0.0000,0.0000,3.1416} "
        "{Mount P3AT} {Link 1} {Parent -1} {Location 0.0000,0.0000,0.1000} {Orientation 0.0000,0.0000,0.0000} "
        "{Link 2} {Parent 0} {Location 0.3000,0.0000,0.0000} {Orientation 0.0000,1.5708,0.0000}",
    ),
]


@pytest.mark.parametrize(("msg", "line"), GOLDEN, ids=[g[1][:48] for g in GOLDEN])
def test_golden_lines_are_byte_exact(msg: m.Message, line: str) -> None:
    text = format_message(msg)
    assert text == line + "\r\n"
    assert text.encode("ascii") == (line + "\r\n").encode("ascii")


@pytest.mark.parametrize(("msg", "line"), GOLDEN, ids=[g[1][:48] for g in GOLDEN])
def test_golden_lines_read_back_to_the_same_text(msg: m.Message, line: str) -> None:
    assert format_message(parse_message(line + "\r\n")) == line + "\r\n"


def test_golden_covers_every_message_and_reading_type() -> None:
    kinds = {type(msg) for msg, _ in GOLDEN}
    assert kinds == set(m.Message.__args__)
    reading_kinds = {type(msg.reading) for msg, _ in GOLDEN if isinstance(msg, m.SensorMessage)}
    assert reading_kinds == set(r.Reading.__args__)


def test_laser_line_of_181_beams_keeps_the_beam_count() -> None:
    ranges = tuple(round(1.0 + i * 0.01, 4) for i in range(181))
    reading = r.RangeScanReading(
        sensor_type="RangeScanner",
        name="Scanner1",
        resolution_rad=math.radians(1.0),
        fov_rad=math.pi,
        ranges_m=ranges,
    )
    text = format_reading(reading, 31.25)
    assert text == format_message(m.SensorMessage(time=31.25, reading=reading))
    parsed = parse_message(text).reading
    assert math.floor(parsed.fov_rad / parsed.resolution_rad) + 1 == 181
    assert parsed.ranges_m == ranges
    assert len(text) < 4096


def test_empty_scan_and_empty_packed_readings() -> None:
    scan = r.RangeScanReading(sensor_type="IRScanner", name="s", resolution_rad=0.1, fov_rad=1.0, ranges_m=())
    assert format_reading(scan) == "SEN {Type IRScanner} {Name s} {Resolution 0.1000} {FOV 1.0000} {Range}\r\n"
    assert parse_message(format_reading(scan)) == m.SensorMessage(time=None, reading=scan)
    assert format_reading(r.RangeReading(sensor_type="Sonar", items=())) == "SEN {Type Sonar}\r\n"
    assert format_reading(r.EncoderReading(items=())) == "SEN {Type Encoder}\r\n"
    assert format_reading(r.TouchReading(items=())) == "SEN {Type Touch}\r\n"


# --------------------------------------------------------------------------- client-side parsing


def test_parse_accepts_udk_separate_segments() -> None:
    sonar = parse_message("SEN {Time 477.7582} {Type Sonar} {Name F1} {Range 2.51}")
    assert sonar.reading == r.RangeReading(sensor_type="Sonar", items=(r.RangeItem(name="F1", range_m=2.51),))
    enc = parse_message("SEN {Type Encoder} {Name W1} {Tick 12} {Name W2} {Tick -3}")
    assert enc.reading.items == (r.EncoderItem(name="W1", tick=12), r.EncoderItem(name="W2", tick=-3))
    touch = parse_message("SEN {Type Touch} {Name T1} {Touch True}")
    assert touch.reading.items == (r.TouchItem(name="T1", touching=True),)
    geo = parse_message(
        "GEO {Type RangeScanner} {Name lms200} {Location 0.21,0.00,-0.20} {Orientation 0.00,0.00,0.00} {Mount P3AT}"
    )
    assert geo == m.ItemGeometry(
        item_type="RangeScanner",
        items=(m.ItemPose(name="lms200", location=(0.21, 0.0, -0.2), orientation=(0.0, 0.0, 0.0), mount="P3AT"),),
    )


def test_parse_unknown_sensor_and_message_types() -> None:
    line = "SEN {Time 1.0} {Type CO2Sensor} {Name CO2} {Gas CO2} {Density 0.00}"
    parsed = parse_message(line)
    assert isinstance(parsed, m.UnknownMessage) and parsed.type == "SEN"
    assert format_message(parsed) == line + "\r\n"
    assert parse_message("ACTSTA {Name arm}") == m.UnknownMessage(type="ACTSTA", segments=(Segment("Name", "arm"),))


@pytest.mark.parametrize(
    "line",
    [
        "STA {Type GroundVehicle} {Time x}",
        "STA {Type GroundVehicle} {Time 1.0}",
        "NFO {StartPoses 2} {A 1,2,3 0,0,0}",
        "NFO {StartPoses 1} {A 1,2,3}",
        "SEN {Type RangeScanner} {Name s} {Resolution 0.1} {FOV 1} {Range 1,x}",
        "SEN {Type Sonar} {Name F1 Range}",
        "SEN {Type GPS} {Name GPS} {Latitude 39,8.0,Q} {Fix 1} {Satellites 5}",
        "SEN {Type RFID} {Name RFID} {ID 5}",
        "SEN {Type VictSensor} {Name V} {Location 1,2,3}",
        "GEO {Type Sonar} {Name F1 Location 1,2,3}",
        "RES {Time 1.00} {Type RFID} {Name RFID}",
        "STEPPED",
        "DIE {Killer x}",
        "NFO {Gametype x}",
        "",
        "SEN {Type Sonar",
    ],
)
def test_parse_message_rejects_malformed_lines(line: str) -> None:
    with pytest.raises(ProtocolError):
        parse_message(line)


def test_format_message_rejects_non_messages() -> None:
    with pytest.raises(TypeError):
        format_message("STA")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        format_reading(object())  # type: ignore[arg-type]


# --------------------------------------------------------------------------- round trips
# Values are drawn at the printed precision, so they read back exactly.

_names = st.text(
    alphabet=st.sampled_from("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-"),
    min_size=1,
    max_size=12,
).filter(lambda s: s.lower() not in {"none"})
_words = _names
_texts = (
    st.text(
        alphabet=st.characters(min_codepoint=32, max_codepoint=126, blacklist_characters="{}"),
        min_size=1,
        max_size=24,
    )
    .map(str.strip)
    .filter(bool)
)


def _dec(places: int, bound: int = 10**6) -> st.SearchStrategy[float]:
    scale = 10**places
    return st.integers(-bound * scale, bound * scale).map(lambda k: k / scale)


_f2 = _dec(2)
_f4 = _dec(4)
_time2 = st.integers(0, 10**8).map(lambda k: k / 100)
_time4 = st.integers(0, 10**10).map(lambda k: k / 10**4)
_angle = st.integers(0, 62831).map(lambda k: k / 10**4)  # [0, 2 pi) at 4 decimals
_v2 = st.tuples(_f2, _f2, _f2)
_v4 = st.tuples(_f4, _f4, _f4)
_va = st.tuples(_angle, _angle, _angle)
_positive4 = st.integers(1, 10**6).map(lambda k: k / 10**4)
_ints = st.integers(-(10**6), 10**6)


def _tuples(strategy: st.SearchStrategy, min_size: int = 0, max_size: int = 6) -> st.SearchStrategy:
    return st.lists(strategy, min_size=min_size, max_size=max_size).map(tuple)


_pose = st.builds(m.StartPose, name=_names, location=_v2, rotation=_v2)
_gps_coord = st.tuples(st.integers(0, 179), st.integers(0, 599999).map(lambda k: k / 10**4), st.sampled_from("NSEW"))

READINGS = st.one_of(
    st.builds(
        r.RangeReading,
        sensor_type=st.sampled_from(["Sonar", "IR", "RangeSensor"]),
        items=_tuples(st.builds(r.RangeItem, name=_names, range_m=_f4), 1),
    ),
    st.builds(
        r.RangeScanReading,
        sensor_type=st.sampled_from(["RangeScanner", "IRScanner"]),
        name=_names,
        resolution_rad=_positive4,
        fov_rad=_positive4,
        ranges_m=_tuples(_f4, 0, 200),
    ),
    st.builds(
        r.RangeScan3DReading,
        name=_names,
        resolution_rad=st.tuples(_positive4, _positive4),
        fov_rad=st.tuples(_positive4, _positive4),
        ranges_m=_tuples(_f4, 0, 50),
        sensor_type=st.sampled_from(["RangeScanner3D", "3DRangeScanner"]),
    ),
    st.builds(
        r.RangeImageReading,
        name=_names,
        pixels=st.tuples(st.integers(1, 640), st.integers(1, 480)),
        fov_rad=st.tuples(_positive4, _positive4),
        ranges_m=_tuples(_dec(3), 0, 50),
        frames=st.just(4),
        frame=st.integers(0, 3),
    ),
    st.builds(r.OdometryReading, name=_names, x_m=_f4, y_m=_f4, theta_rad=_f4),
    st.builds(r.EncoderReading, items=_tuples(st.builds(r.EncoderItem, name=_names, tick=_ints), 1)),
    st.builds(
        r.PoseReading,
        sensor_type=st.sampled_from(["GroundTruth", "INS"]),
        name=_names,
        location=_v4,
        orientation=_va,
    ),
    st.builds(r.OrientationReading, name=_names, orientation=_va),
    st.builds(r.TouchReading, items=_tuples(st.builds(r.TouchItem, name=_names, touching=st.booleans()), 1)),
    st.builds(
        r.GpsReading, name=_names, fix=st.just(True), satellites=st.integers(0, 24),
        latitude=_gps_coord, longitude=_gps_coord,
    ),
    st.builds(r.GpsReading, name=_names, fix=st.just(False), satellites=st.integers(0, 24)),
    st.builds(r.TachometerReading, name=_names, velocities_rad_s=_tuples(_f4, 1), positions_rad=_tuples(_f4, 1)),
    st.builds(r.SoundReading, name=_names, loudness_db=_f4, duration_s=_f4),
    st.builds(r.HumanMotionReading, name=_names, probability=_f4),
    st.builds(
        r.ImuReading, name=_names, acceleration=_v4, angular_velocity=_v4,
        angular_acceleration=_v4, orientation=_v4,
    ),
    st.builds(r.VictimReading, name=_names, parts=_tuples(st.builds(r.VictimPart, part_name=_names, location=_v4), 1)),
    st.builds(r.VictimReading, name=st.just("VictSensor"), parts=st.just(())),
    st.builds(
        r.RfidReading,
        name=_names,
        tags=_tuples(
            st.builds(r.RfidTag, tag_id=st.integers(0, 10**9), location=_v4, memory=st.none() | _texts)
        ),
    ),
)  # fmt: skip

MESSAGE_STRATEGIES = {
    m.GameInfo: st.builds(m.GameInfo, gametype=_names, level=_names, time_limit=st.integers(0, 1000)),
    m.StartPoses: st.builds(m.StartPoses, poses=_tuples(_pose)),
    m.PathNodes: st.builds(m.PathNodes, nodes=_tuples(_pose)),
    m.ClosestPathNode: st.builds(m.ClosestPathNode, name=_names, location=_v2),
    m.StatusMessage: st.builds(
        _sta,
        _time2,
        front_steer=_f4,
        rear_steer=_f4,
        joints=_tuples(st.tuples(_names.filter(lambda n: n.lower() not in {
            "type", "time", "frontsteer", "rearsteer", "lighttoggle", "lightintensity", "battery", "view"
        }), _f4), 0, 4),
        light_toggle=st.booleans(),
        light_intensity=st.integers(0, 100),
        battery_s=st.integers(0, 10**5),
        view=st.integers(-1, 3),
        vehicle_type=st.sampled_from(["GroundVehicle", "LeggedRobot", "NauticalVehicle", "StaticPlatform"]),
    ) | st.builds(  # an aerial robot's line has no steer angles or joints
        _sta, _time2, light_toggle=st.booleans(), vehicle_type=st.just("AerialVehicle"),
        light_intensity=st.integers(0, 100), battery_s=st.integers(0, 10**5), view=st.integers(-1, 3),
    ),
    m.SensorMessage: st.builds(m.SensorMessage, time=st.none() | _time4, reading=READINGS),
    m.RobotGeometry: st.builds(
        m.RobotGeometry, vehicle_type=_names, class_name=_names, dimensions=_v4, cog=_v4,
        wheel_radius=st.none() | _f4, wheel_separation=st.none() | _f4, wheel_base=st.none() | _f4,
    ),
    m.RobotConfiguration: st.builds(
        m.RobotConfiguration, vehicle_type=_names, class_name=_names, steering_type=_names,
        mass_kg=_f4, max_speed=_f4, max_torque=_f4, max_front_steer=_f4, max_rear_steer=_f4,
    ),
    m.ItemGeometry: st.builds(
        m.ItemGeometry,
        item_type=_names.filter(lambda n: n.lower() != "mispkg"),
        items=_tuples(st.builds(m.ItemPose, name=_names, location=_v4, orientation=_v4, mount=_names), 1),
    ),
    m.EmptyGeometry: st.builds(m.EmptyGeometry, item_type=_names, name=st.none() | _names),
    m.ItemConfiguration: st.builds(
        m.ItemConfiguration,
        item_type=_names.filter(lambda n: n.lower() != "mispkg"),
        items=_tuples(
            st.builds(
                m.ItemConf,
                name=_names,
                fields=_tuples(
                    st.tuples(_names.filter(lambda k: k.lower() not in {"name", "type", "steeringtype"}), _texts),
                    1, 5,
                ),
            ),
            1, 4,
        ),
    ),
    m.EmptyConfiguration: st.builds(m.EmptyConfiguration, item_type=_names, name=st.none() | _names),
    m.MisPkgGeometry: st.builds(
        m.MisPkgGeometry,
        packages=_tuples(
            st.builds(
                m.PackageGeometry,
                name=_names,
                links=_tuples(
                    st.builds(m.LinkGeometry, link=st.integers(1, 20), parent_link=st.integers(-1, 20),
                              location=_v4, orientation=_v4), 1, 4,
                ),
            ),
            1, 3,
        ),
    ),
    m.MisPkgConfiguration: st.builds(
        m.MisPkgConfiguration,
        packages=_tuples(
            st.builds(
                m.PackageConfiguration,
                name=_names,
                links=_tuples(
                    st.builds(m.LinkConfiguration, link=st.integers(1, 20),
                              joint_type=st.sampled_from(["Revolute", "Prismatic", "Scissor"]),
                              max_speed=_f4, max_torque=_f4, min_range=_f4, max_range=_f4), 1, 4,
                ),
            ),
            1, 3,
        ),
    ),
    m.MisPkgMessage: st.builds(
        m.MisPkgMessage, time=_time2, state=st.builds(r.PackageState, name=_names,
        links=_tuples(st.builds(r.PackageLink, link=st.integers(1, 20), value=_f4, torque=_f4))),
    ),
    m.ActuatorConfiguration: st.builds(
        m.ActuatorConfiguration,
        actuators=_tuples(
            st.builds(
                m.ActuatorConfig,
                name=_names,
                links=_tuples(
                    st.builds(m.ActuatorLinkConfiguration, link=st.integers(1, 20),
                              joint_type=st.sampled_from(["Revolute", "Prismatic"]),
                              max_torque=_f4, min_value=_f4, max_value=_f4), 1, 4,
                ),
            ),
            1, 3,
        ),
    ),
    m.ActuatorGeometry: st.builds(
        m.ActuatorGeometry,
        actuators=_tuples(
            st.builds(
                m.ActuatorPose, name=_names, location=_v4, orientation=_v4, mount=_names,
                links=_tuples(
                    st.builds(m.ActuatorLinkGeometry, link=st.integers(1, 20), parent=st.integers(-1, 20),
                              location=_v4, orientation=_v4), 0, 4,
                ),
            ),
            1, 3,
        ),
    ),
    m.ActuatorStatus: st.builds(
        m.ActuatorStatus, time=_time4, name=_names,
        links=_tuples(st.builds(r.PackageLink, link=st.integers(1, 20), value=_f4, torque=_f4)),
        gripper=st.none() | st.integers(0, 1),
    ),
    m.Result: st.builds(
        m.Result, time=_time2, item_type=_names.filter(lambda n: n not in {"Camera", "Viewports"}),
        name=st.none() | _names, status=_names, extra=_tuples(st.tuples(_names, _texts), 0, 3),
    ),
    m.CameraZoomResult: st.builds(
        m.CameraZoomResult, time=_time2,
        cameras=_tuples(st.builds(m.CameraZoom, name=_names, fov=_f4, status=_names), 1, 3),
    ),
    m.ViewportsResult: st.builds(
        m.ViewportsResult, time=_time2, config=_names, config_status=_names,
        viewports=_tuples(st.builds(m.ViewportState, index=st.integers(1, 4), camera=_names, status=_names), 0, 4),
    ),
    m.EffecterStatus: st.builds(
        m.EffecterStatus, time=st.none() | _time4, effecter_type=_names, name=_names,
        status=st.none() | _names,
        extra=_tuples(
            st.tuples(_names.filter(lambda k: k.lower() not in {"time", "type", "name", "status"}),
                      st.just("") | _texts), 0, 3,
        ),
    ),
    m.Die: st.builds(m.Die, killer=_texts, damage_type=_texts),
    m.Stepped: st.builds(m.Stepped, time=_time4),
    m.Pong: st.builds(m.Pong, id=st.none() | _names, time=st.none() | _time4),
    m.ErrorReply: st.builds(m.ErrorReply, command=_names.map(str.upper), reason=_texts),
    m.UnknownMessage: st.builds(
        m.UnknownMessage,
        type=_names.map(str.upper).filter(
            lambda t: t not in {"NFO", "STA", "SEN", "GEO", "CONF", "MISSTA", "RES", "EFF", "DIE", "STEPPED",
                                "ERROR"}
        ),
        segments=_tuples(st.builds(Segment, _names, st.just("") | _texts), 0, 4),
    ),
}  # fmt: skip


def test_every_message_type_has_a_round_trip_strategy() -> None:
    assert set(MESSAGE_STRATEGIES) == set(m.Message.__args__)


@pytest.mark.parametrize("kind", list(MESSAGE_STRATEGIES), ids=lambda k: k.__name__)
@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_round_trip(kind: type, data: st.DataObject) -> None:
    msg = data.draw(MESSAGE_STRATEGIES[kind])
    text = format_message(msg)
    assert text.endswith("\r\n") and "\r" not in text[:-2] and "\n" not in text[:-2]
    assert "  " not in text.split("{", 1)[0]
    parsed = parse_message(text)
    assert format_message(parsed) == text
    assert parsed == msg


_GARBAGE = st.sampled_from(
    ["", "x", "nan", "inf", "1e400", "-1", "1,2", "1,,2", "a b c", "Location", "1 2 3 4 5", "\ufffd"]
)


@st.composite
def _mutated_golden_lines(draw: st.DrawFn) -> str:
    """A golden line with some segment contents replaced or removed."""
    line = draw(st.sampled_from([g[1] for g in GOLDEN]))
    head, *segments = line.split(" {")
    for _ in range(draw(st.integers(1, 3))):
        if not segments:
            break
        i = draw(st.integers(0, len(segments) - 1))
        action = draw(st.sampled_from(["value", "drop", "key"]))
        key = segments[i].split(" ", 1)[0].rstrip("}")
        if action == "drop":
            del segments[i]
        elif action == "value":
            segments[i] = "%s %s}" % (key, draw(_GARBAGE))
        else:
            segments[i] = "%s}" % draw(_GARBAGE.filter(bool).map(lambda g: g.replace(" ", "")))
    return " {".join([head, *segments])


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=80) | _mutated_golden_lines())
def test_parse_message_raises_only_protocol_error(line: str) -> None:
    try:
        parse_message(line)
    except ProtocolError:
        pass


# ---- readings sent in several layouts (declare.Variants), joined fields and item groups


def test_a_gps_without_a_fix_leaves_out_the_coordinates_it_may_still_hold():
    fix = r.GpsReading("GPS", True, 8, (39, 8.0341, "N"), (77, 12.5, "W"))
    lost = r.GpsReading("GPS", False, 2, (39, 8.0341, "N"), (77, 12.5, "W"))
    assert format_reading(fix, 3.0) == (
        "SEN {Time 3.0000} {Type GPS} {Name GPS} {Latitude 39,8.0341,N} {Longitude 77,12.5000,W} "
        "{Fix 1} {Satellites 8}\r\n"
    )
    assert format_reading(lost, 3.0) == "SEN {Time 3.0000} {Type GPS} {Name GPS} {Fix 0} {Satellites 2}\r\n"
    # the coordinates are read whenever a line has them
    assert parse_message("SEN {Type GPS} {Name G} {Fix 0} {Satellites 1} {Latitude 1,2.5,S}\r\n").reading.latitude == (
        1,
        2.5,
        "S",
    )


def test_a_split_3d_sweep_sends_a_line_a_row_that_reads_back_as_its_row():
    sweep = r.RangeScan3DReading("S", (0.1, 0.2), (0.5, 1.0), (1.0, 2.0, 3.0, 4.0), frames=2, split=True)
    lines = format_reading(sweep, 1.0).split("\r\n")[:-1]
    assert lines == [
        "SEN {Time 1.0000} {Type RangeScanner3D} {Name S} {Frames 2} {Frame 0} {Resolution 0.1000,0.2000} "
        "{FOV 0.5000,1.0000} {Range 1.0000,2.0000}",
        "SEN {Time 1.0000} {Type RangeScanner3D} {Name S} {Frames 2} {Frame 1} {Resolution 0.1000,0.2000} "
        "{FOV 0.5000,1.0000} {Range 3.0000,4.0000}",
    ]
    row = parse_message(lines[1] + "\r\n").reading
    assert (row.frames, row.frame, row.split, row.ranges_m) == (2, 1, True, (3.0, 4.0))
    whole = parse_message("SEN {Type RangeScanner3D} {Name S} {Resolution 0.1,0.2} {FOV 0.5,1} {Range}\r\n").reading
    assert (whole.frame, whole.split, whole.ranges_m) == (None, False, ())


def test_joined_fields_and_item_groups_print_and_refuse_by_their_keys():
    assert format_reading(r.OdometryReading("Odo", 1.5, -2.25, 0.3)) == (
        "SEN {Type Odometry} {Name Odo} {Pose 1.5000,-2.2500,0.3000}\r\n"
    )
    with pytest.raises(ProtocolError, match="bad value '1,2' for key Pose: expected 3 comma-separated numbers"):
        parse_message("SEN {Type Odometry} {Name Odo} {Pose 1,2}\r\n")
    tags = r.RfidReading(
        "R", (r.RfidTag(3, (1.0, 2.0, 0.0), ""), r.RfidTag(4, (0.0, 0.0, 0.0), "a b"), r.RfidTag(5, (0, 0, 0)))
    )
    assert format_reading(tags) == (
        "SEN {Type RFID} {Name R} {ID 3} {Location 1.0000,2.0000,0.0000} {Mem} "
        "{ID 4} {Location 0.0000,0.0000,0.0000} {Mem a b} {ID 5} {Location 0.0000,0.0000,0.0000}\r\n"
    )
    with pytest.raises(ProtocolError, match=r"\{ID 7\} has no \{Location x,y,z\}"):
        parse_message("SEN {Type RFID} {Name R} {ID 7} {Mem x}\r\n")
