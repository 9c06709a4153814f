within;
package NavVehicles
  "Kinematic vehicles on the WGS-84 ellipsoid with navfmu's truth outputs"

  partial model WgsVehicle
    "Point-mass kinematics on WGS-84: position integrated from a speed, a heading rate and a
     flight-path angle given by the vehicle's profile; outputs the truth contract plus the
     inertial body rates and the specific force"
    parameter Real lat0 = 0.6998770300497261 "start latitude [rad]";
    parameter Real lon0 = 2.069960492865275 "start longitude [rad]";
    parameter Real h0 = 100.0 "start height above the ellipsoid [m]";
    parameter Real yaw0 = 0.0 "start heading [rad]";
    constant Real a = 6378137.0 "WGS-84 semi-major axis [m]";
    constant Real f = 1.0 / 298.257223563 "WGS-84 flattening";
    constant Real e2 = f * (2.0 - f) "first eccentricity squared";
    constant Real b = a * (1.0 - f) "semi-minor axis [m]";
    constant Real omega_ie = 7.292115e-5 "earth rate [rad/s]";
    constant Real gm = 3.986004418e14 "earth's gravitational constant [m3/s2]";
    constant Real gamma_e = 9.7803253359 "normal gravity at the equator [m/s2]";
    constant Real gamma_p = 9.8321849378 "normal gravity at the poles [m/s2]";
    // states are offsets from the start parameters, with literal starts: a state whose start
    // is bound to a parameter reports the compiled-in start in initialization mode
    Real dlat(start = 0.0, fixed = true) "latitude offset [rad]";
    Real dlon(start = 0.0, fixed = true) "longitude offset [rad]";
    Real dh(start = 0.0, fixed = true) "height offset [m]";
    Real dyaw(start = 0.0, fixed = true) "heading offset [rad]";
    // the profile (defined by each vehicle)
    Real speed "speed over the earth [m/s]";
    Real speed_rate "its derivative [m/s2]";
    Real yaw_rate "heading rate [rad/s]";
    Real gamma "flight-path angle (= pitch) [rad]";
    Real gamma_rate "its derivative [rad/s]";
    Real roll "bank angle [rad]";
    Real roll_rate "its derivative [rad/s]";
    // kinematics
    Real lat, lon, h, yaw, rn, re, sl, cl;
    Real cr, sr, cp, sp, cy, sy;
    Real win_n, win_e, win_d "omega_in^n: earth plus transport rate [rad/s]";
    Real cor_n, cor_e, cor_d "2 omega_ie^n + omega_en^n [rad/s]";
    Real fn, fe, fd "specific force in NED [m/s2]";
    Real g "normal gravity [m/s2]";
    output Real truth_time(unit = "s") "time the sample is valid for";
    output Real truth_lat(unit = "rad") "WGS-84 latitude";
    output Real truth_lon(unit = "rad") "WGS-84 longitude";
    output Real truth_h(unit = "m") "height above the ellipsoid";
    output Real truth_vn(unit = "m/s") "north velocity";
    output Real truth_ve(unit = "m/s") "east velocity";
    output Real truth_vd(unit = "m/s") "down velocity";
    output Real truth_roll(unit = "rad") "roll";
    output Real truth_pitch(unit = "rad") "pitch";
    output Real truth_yaw(unit = "rad") "yaw in (-pi, pi]";
    output Real body_rate_x(unit = "rad/s") "inertial angular rate, body x";
    output Real body_rate_y(unit = "rad/s") "inertial angular rate, body y";
    output Real body_rate_z(unit = "rad/s") "inertial angular rate, body z";
    output Real specific_force_x(unit = "m/s2") "specific force, body x";
    output Real specific_force_y(unit = "m/s2") "specific force, body y";
    output Real specific_force_z(unit = "m/s2") "specific force, body z";
  equation
    lat = lat0 + dlat;
    lon = lon0 + dlon;
    h = h0 + dh;
    yaw = yaw0 + dyaw;
    sl = sin(lat);
    cl = cos(lat);
    rn = a * (1.0 - e2) / (1.0 - e2 * sl * sl) ^ 1.5;
    re = a / sqrt(1.0 - e2 * sl * sl);
    truth_vn = speed * cos(gamma) * cos(yaw);
    truth_ve = speed * cos(gamma) * sin(yaw);
    truth_vd = -speed * sin(gamma);
    der(dlat) = truth_vn / (rn + h);
    der(dlon) = truth_ve / ((re + h) * cl);
    der(dh) = -truth_vd;
    der(dyaw) = yaw_rate;
    truth_time = time;
    truth_lat = lat;
    truth_lon = lon;
    truth_h = h;
    truth_roll = roll;
    truth_pitch = gamma;
    truth_yaw = atan2(sin(yaw), cos(yaw));
    cr = cos(roll);
    sr = sin(roll);
    cp = cos(gamma);
    sp = sin(gamma);
    cy = cos(yaw);
    sy = sin(yaw);
    win_n = omega_ie * cl + truth_ve / (re + h);
    win_e = -truth_vn / (rn + h);
    win_d = -omega_ie * sl - truth_ve * sl / cl / (re + h);
    cor_n = win_n + omega_ie * cl;
    cor_e = win_e;
    cor_d = win_d - omega_ie * sl;
    g = gamma_e * (1.0 + (b * gamma_p - a * gamma_e) / (a * gamma_e) * sl * sl)
        / sqrt(1.0 - e2 * sl * sl)
        * (1.0 - 2.0 / a * (1.0 + f + omega_ie ^ 2 * a ^ 2 * b / gm - 2.0 * f * sl * sl) * h
           + 3.0 * h ^ 2 / a ^ 2);
    // specific force in NED: dv/dt + (2 omega_ie + omega_en) x v - g
    fn = speed_rate * cp * cy - speed * sp * gamma_rate * cy - speed * cp * sy * yaw_rate
         + cor_e * truth_vd - cor_d * truth_ve;
    fe = speed_rate * cp * sy - speed * sp * gamma_rate * sy + speed * cp * cy * yaw_rate
         + cor_d * truth_vn - cor_n * truth_vd;
    fd = -speed_rate * sp - speed * cp * gamma_rate
         + cor_n * truth_ve - cor_e * truth_vn - g;
    // body axes: the Euler-rate part plus C_bn (omega_ie + omega_en), C_bn f
    body_rate_x = roll_rate - yaw_rate * sp
                  + cp * cy * win_n + cp * sy * win_e - sp * win_d;
    body_rate_y = gamma_rate * cr + yaw_rate * sr * cp
                  + (sr * sp * cy - cr * sy) * win_n + (sr * sp * sy + cr * cy) * win_e
                  + sr * cp * win_d;
    body_rate_z = -gamma_rate * sr + yaw_rate * cr * cp
                  + (cr * sp * cy + sr * sy) * win_n + (cr * sp * sy - sr * cy) * win_e
                  + cr * cp * win_d;
    specific_force_x = cp * cy * fn + cp * sy * fe - sp * fd;
    specific_force_y = (sr * sp * cy - cr * sy) * fn + (sr * sp * sy + cr * cy) * fe + sr * cp * fd;
    specific_force_z = (cr * sp * cy + sr * sy) * fn + (cr * sp * sy - sr * cy) * fe + cr * cp * fd;
  end WgsVehicle;

  function window "Smooth window: about 1 between t1 and t2, 0 outside, tanh edges of width tau"
    input Real t;
    input Real t1;
    input Real t2;
    input Real tau;
    output Real w;
  algorithm
    w := 0.5 * (tanh((t - t1) / tau) - tanh((t - t2) / tau));
  end window;

  function window_rate "Time derivative of window"
    input Real t;
    input Real t1;
    input Real t2;
    input Real tau;
    output Real w;
  algorithm
    w := 0.5 / tau * (tanh((t - t2) / tau) ^ 2 - tanh((t - t1) / tau) ^ 2);
  end window_rate;

  model FixedWingAircraft
    "Kinematic fixed-wing aircraft: straight flight, a coordinated 180 deg turn at 3 deg/s,
     straight again, a 4.6 deg climb and level flight (no events: smooth tanh edges)"
    extends WgsVehicle(h0 = 1000.0);
    parameter Real airspeed = 50.0 "speed [m/s]";
    parameter Real turn_rate = 0.05235987755982988 "3 deg/s [rad/s]";
    parameter Real turn_start = 60.0 "[s]";
    parameter Real turn_end = 120.0 "[s]: 180 deg at 3 deg/s";
    parameter Real climb_angle = 0.08028514559173916 "4.6 deg [rad]";
    parameter Real climb_start = 200.0 "[s]";
    parameter Real climb_end = 300.0 "[s]";
    parameter Real edge = 2.0 "width of the tanh edges [s]";
    constant Real g0 = 9.80665 "standard gravity of the coordinated-turn bank [m/s2]";
    Real turn, turn_rate_rate;
  equation
    speed = airspeed;
    speed_rate = 0.0;
    turn = turn_rate * window(time, turn_start, turn_end, edge);
    turn_rate_rate = turn_rate * window_rate(time, turn_start, turn_end, edge);
    yaw_rate = turn;
    roll = atan(airspeed * turn / g0);
    roll_rate = airspeed * turn_rate_rate / g0 / (1.0 + (airspeed * turn / g0) ^ 2);
    gamma = climb_angle * window(time, climb_start, climb_end, edge);
    gamma_rate = climb_angle * window_rate(time, climb_start, climb_end, edge);
  end FixedWingAircraft;

  model GroundVehicle
    "Car on a road loop: 400 m straights joined by two 180 deg turns of 50 m radius, slowing
     from 15 to 8 m/s for each turn, over a 2 % rise and fall on the far straight"
    extends WgsVehicle(h0 = 50.0);
    parameter Real cruise = 15.0 "speed on the straights [m/s]";
    parameter Real corner = 8.0 "speed in the turns [m/s]";
    parameter Real radius = 50.0 "turn radius [m]";
    parameter Real grade = 0.02 "road grade of the rise and fall [rad]";
    parameter Real edge = 1.5 "width of the tanh edges [s]";
    // schedule: straight 400 m at 15 m/s ~ 26.7 s, brake, turn pi*50/8 = 19.6 s, accelerate
    parameter Real t_turn1 = 30.0 "[s]";
    parameter Real t_turn2 = 85.0 "[s]";
    parameter Real turn_time = 19.634954084936208 "pi radius / corner [s]";
    parameter Real slow_lead = 4.0 "braking before a turn [s]";
    parameter Real t_rise = 55.0 "start of the 10 s rise; the 10 s fall starts 13 s later [s]";
    Real slow, slow_rate, turn_rate_turn;
  equation
    slow = window(time, t_turn1 - slow_lead, t_turn1 + turn_time + slow_lead, edge)
           + window(time, t_turn2 - slow_lead, t_turn2 + turn_time + slow_lead, edge);
    slow_rate = window_rate(time, t_turn1 - slow_lead, t_turn1 + turn_time + slow_lead, edge)
                + window_rate(time, t_turn2 - slow_lead, t_turn2 + turn_time + slow_lead, edge);
    speed = cruise - (cruise - corner) * slow;
    speed_rate = -(cruise - corner) * slow_rate;
    turn_rate_turn = corner / radius;
    yaw_rate = turn_rate_turn * (window(time, t_turn1, t_turn1 + turn_time, edge)
                                 + window(time, t_turn2, t_turn2 + turn_time, edge));
    roll = 0.0;
    roll_rate = 0.0;
    gamma = grade * (window(time, t_rise, t_rise + 10.0, edge)
                     - window(time, t_rise + 13.0, t_rise + 23.0, edge));
    gamma_rate = grade * (window_rate(time, t_rise, t_rise + 10.0, edge)
                          - window_rate(time, t_rise + 13.0, t_rise + 23.0, edge));
  end GroundVehicle;
end NavVehicles;
