;;;; The costmap metadata predicates.
;;;;
;;;; They take no robot argument: an environment, a robot description or the user declares
;;;; them in a fact group that lists them as extendable, e.g.
;;;;   (def-fact-group my-metadata (costmap:costmap-size) (<- (costmap:costmap-size 12 12)))
;;;; and consumers take the first solution.
;;;;
;;;; Several robot descriptions may be loaded in one image.  A description that should not
;;;; impose its values on the others states them keyed by its robot name through
;;;; ROBOT-COSTMAP-METADATA, e.g. (<- (robot-costmap-metadata :pr2 (costmap-padding 0.3))).
;;;; The clauses below come before every other group's clauses and answer from the keyed
;;;; facts of the current robot (ROB-INT:*ROBOT-NAME*) first; with no current robot, from
;;;; the keyed facts of any robot.  Unkeyed clauses of later groups follow.

(in-package :cram-location-costmap)

(def-fact-group location-costmap-metadata-interface
    (costmap-size costmap-origin costmap-resolution
     costmap-padding costmap-manipulation-padding
     costmap-in-reach-distance costmap-reach-minimal-distance
     visibility-costmap-size orientation-samples orientation-sample-step
     robot-costmap-metadata)

  (<- (robot-costmap-metadata ?robot-name ?metadata-fact) (fail))

  (<- (current-robot-costmap-metadata ?metadata-fact)
    (symbol-value rob-int:*robot-name* ?current)
    (-> (lisp-pred identity ?current)
        (robot-costmap-metadata ?current ?metadata-fact)
        (robot-costmap-metadata ?_ ?metadata-fact)))

  (<- (costmap-size ?width ?height)
    (current-robot-costmap-metadata (costmap-size ?width ?height)))
  (<- (costmap-origin ?x ?y)
    (current-robot-costmap-metadata (costmap-origin ?x ?y)))
  (<- (costmap-resolution ?resolution)
    (current-robot-costmap-metadata (costmap-resolution ?resolution)))
  (<- (costmap-padding ?padding)
    (current-robot-costmap-metadata (costmap-padding ?padding)))
  (<- (costmap-manipulation-padding ?padding)
    (current-robot-costmap-metadata (costmap-manipulation-padding ?padding)))
  (<- (costmap-in-reach-distance ?distance)
    (current-robot-costmap-metadata (costmap-in-reach-distance ?distance)))
  (<- (costmap-reach-minimal-distance ?distance)
    (current-robot-costmap-metadata (costmap-reach-minimal-distance ?distance)))
  (<- (visibility-costmap-size ?radius)
    (current-robot-costmap-metadata (visibility-costmap-size ?radius)))
  (<- (orientation-samples ?count)
    (current-robot-costmap-metadata (orientation-samples ?count)))
  (<- (orientation-sample-step ?angle)
    (current-robot-costmap-metadata (orientation-sample-step ?angle))))

(rob-int::define-predicate-documentation
  (costmap-size "(costmap-size ?width ?height): the extent of a location costmap in metres.")
  (costmap-origin "(costmap-origin ?x ?y): the map-frame position of the costmap's corner
with the smallest coordinates.")
  (costmap-resolution "(costmap-resolution ?resolution): the costmap cell size in metres.")
  (costmap-padding "(costmap-padding ?padding): the distance the robot base keeps from
obstacles, in metres.")
  (costmap-manipulation-padding "(costmap-manipulation-padding ?padding): the obstacle
distance used for base poses while manipulating, in metres.")
  (costmap-in-reach-distance "(costmap-in-reach-distance ?distance): the farthest distance
from the base at which the robot can reach, in metres.")
  (costmap-reach-minimal-distance "(costmap-reach-minimal-distance ?distance): the nearest
distance from the base at which the robot can reach, in metres.")
  (visibility-costmap-size "(visibility-costmap-size ?radius): the radius of the area around
a target sampled for poses that see it, in metres.")
  (orientation-samples "(orientation-samples ?count): how many base orientations are
generated per sampled position.")
  (orientation-sample-step "(orientation-sample-step ?angle): the angle between consecutive
sampled orientations, in radians.")
  (robot-costmap-metadata "(robot-costmap-metadata ?robot-name ?metadata-fact): a metadata
fact such as (costmap-padding 0.3) that holds when ?robot-name is the current robot.")
  (current-robot-costmap-metadata "(current-robot-costmap-metadata ?metadata-fact): the
ROBOT-COSTMAP-METADATA facts of the current robot, or of any robot when none is current."))
