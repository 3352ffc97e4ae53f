"""Golf ball constants shared by the hitting motion's users: the ball model, the controller
(which places the club face against the ball) and the exudyn scene.

A regulation golf ball: 45.9 g, radius 21.35 mm (see REFERENCE "Ball on a putting surface").
"""

#: gravitational acceleration [m/s^2]
G = 9.81
#: golf ball mass [kg]
BALL_MASS = 0.0459
#: golf ball radius [m]
BALL_RADIUS = 0.02135
