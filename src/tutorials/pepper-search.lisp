;;;; Searching a product: where to stand to see a shelf, where to look, and the demo plan.

(in-package :cram-pepper-demo)

(defparameter *viewing-distance* 1.5d0
  "Least distance (metres) between a shelf pose and the base pose the robot looks from.
Pepper's camera is 1.11 m above the floor, below the upper levels: closer to the shelf, the
front edge of the level a product stands on hides more than a tenth of the product (from
1.2 m a milk carton on a level at 1.28 m is 85 % visible, from 1.5 m 91 % or more).")

(defparameter *front-view-angle* (/ pi 6)
  "Largest angle (radians) between the shelf's front direction and the direction from the
shelf pose to the base pose: from further aside the side boards hide the level.")

(defparameter *view-pose-samples* 50
  "How many solutions of the visibility location designator GENERATE-ROBOT-POSE considers.")

(defun shelf-front-direction (shelf-pose)
  "The horizontal unit vector out of the open front of the shelf at SHELF-POSE: the -y axis of
a shelf level link (the shelf offsets move a product pose along it to the front edge)."
  (let* ((v (cl-transforms:rotate (cl-transforms:orientation shelf-pose)
                                  (cl-transforms:make-3d-vector 0 -1 0)))
         (x (cl-transforms:x v)) (y (cl-transforms:y v))
         (norm (sqrt (+ (* x x) (* y y)))))
    (when (< norm 1d-6)
      (error "FACING-POSE: the shelf pose ~s has no horizontal front direction." shelf-pose))
    (cl-transforms:make-3d-vector (/ x norm) (/ y norm) 0)))

(defun facing-pose (target distance)
  "A base pose DISTANCE metres in front of the shelf pose TARGET (out of its open front),
turned towards it."
  (let* ((p (cl-transforms:origin target))
         (direction (shelf-front-direction target))
         (position (cl-transforms:v+ (cl-transforms:make-3d-vector (cl-transforms:x p)
                                                                   (cl-transforms:y p) 0)
                                     (cl-transforms:v* direction distance))))
    (cl-transforms-stamped:make-pose-stamped
     "map" 0d0 position
     (cl-transforms:axis-angle->quaternion
      (cl-transforms:make-3d-vector 0 0 1)
      (atan (- (cl-transforms:y direction)) (- (cl-transforms:x direction)))))))

(defun shelf-view-pose-p (base-pose shelf-pose)
  "True when BASE-POSE stands in front of the open side of the shelf at SHELF-POSE, within
*FRONT-VIEW-ANGLE* of its front direction and at least *VIEWING-DISTANCE* away (less a
millimetre)."
  (let* ((b (cl-transforms:origin base-pose))
         (p (cl-transforms:origin shelf-pose))
         (dx (- (cl-transforms:x b) (cl-transforms:x p)))
         (dy (- (cl-transforms:y b) (cl-transforms:y p)))
         (distance (sqrt (+ (* dx dx) (* dy dy))))
         (front (shelf-front-direction shelf-pose)))
    ;; a millimetre of slack: FACING-POSE stands at *VIEWING-DISTANCE*, up to rounding
    (and (>= distance (- *viewing-distance* 1d-3))
         (>= (/ (+ (* dx (cl-transforms:x front)) (* dy (cl-transforms:y front))) distance)
             (cos *front-view-angle*)))))

(defun generate-robot-pose (?shelf-pose)
  "A base pose from which the robot sees ?SHELF-POSE: the first of the solutions of a
VISIBLE-FOR location designator that stands in front of the shelf (SHELF-VIEW-POSE-P), or a
pose *VIEWING-DISTANCE* in front of the shelf when there is none."
  (let* ((?product-pose-stamped (cl-transforms-stamped:pose->pose-stamped "map" 0 ?shelf-pose))
         (?product-location-designator (desig:a location (pose ?product-pose-stamped)))
         (?robot (rob-int:current-robot-name))
         (to-see-designator (desig:a location (visible-for ?robot)
                                     (location ?product-location-designator)
                                     (object (desig:an object (type :shelf))))))
    (handler-case
        (or (loop repeat *view-pose-samples*
                  for designator = to-see-designator then (desig:next-solution designator)
                  while designator
                  for pose = (desig:reference designator)
                  when (shelf-view-pose-p pose ?shelf-pose)
                    return pose)
            (progn
              (cpl:log-message :info '(pepper-demo) "No visibility costmap solution in front ~
                                                     of the shelf; standing in front of it.")
              (facing-pose ?shelf-pose *viewing-distance*)))
      (desig:designator-error (e)
        (cpl:log-message :warn '(pepper-demo) "No visibility costmap solution (~a); ~
                                               standing in front of the shelf." e)
        (facing-pose ?shelf-pose *viewing-distance*)))))

(defun move-to-location (?pose)
  "Drive to ?POSE."
  (let ((?navigation-goal ?pose))
    (perform (desig:an action (type going)
                       (target (desig:a location (pose ?navigation-goal)))))))

(defun demo-one (?product-name ?shelf-pose-lists)
  "Visit the shelf poses of ?PRODUCT-NAME until it is seen; then point at it and let the human
follow. Returns the perceived product designator or NIL."
  (urdf-proj:with-simulated-robot
    (let ((found nil))
      (dolist (?shelf-pose ?shelf-pose-lists)
        (let ((product-pose (generate-robot-pose ?shelf-pose)))
          (cpl:with-retry-counters ((error-counter 2))
            (cpl:with-failure-handling
                ((common-fail:navigation-pose-unreachable (e)
                   (cpl:log-message :warn '(navigation-failure)
                                    "~a~%Could not move to location...retrying" e)
                   (cpl:do-retry error-counter
                     (setf product-pose (facing-pose ?shelf-pose (+ *viewing-distance* 0.3)))
                     (cpl:retry))
                   (return)))
              (move-to-location product-pose))))
        (setf found (find-product ?product-name ?shelf-pose))
        (when found
          (point-front-right)
          (move-human-to-location)
          (format t "~&There is your product!~%")
          (return)))
      (unless found
        (move-human-to-location)
        (format t "~&Sorry I could not find your product! However, 
		I believe it is supposed to be in this area of the shelf.~%"))
      found)))

(defun find-product (?product-name ?product-pose)
  "Look for ?PRODUCT-NAME at ?PRODUCT-POSE, then right and left of it, turning the base
towards each look target. Returns the perceived designator or NIL."
  (generate-look-directions ?product-pose)
  (let* ((?object-type (get-product-type ?product-name))
         (possible-look-directions `(,*look-center* ,*look-right* ,*look-left*))
         (?looking-direction (first possible-look-directions)))
    (setf possible-look-directions (cdr possible-look-directions))
    (move-to-location (calculate-robot-navigation-goal-towards-target ?looking-direction))
    (look-at-product ?looking-direction)
    (cpl:with-failure-handling
        ((common-fail:perception-object-not-found (e)
           (when possible-look-directions
             (cpl:log-message :warn '(perception-failure) "~a~%Turning head." e)
             (format t "~&Changing viewing direction!~%")
             (setf ?looking-direction (first possible-look-directions))
             (setf possible-look-directions (cdr possible-look-directions))
             (move-to-location (calculate-robot-navigation-goal-towards-target ?looking-direction))
             (look-at-product ?looking-direction)
             (cpl:retry))
           (return nil)))
      (perform (desig:an action (type detecting)
                         (object (desig:an object (type ?object-type))))))))

(defun generate-look-directions (?product-pose)
  "Set *LOOK-CENTER*, *LOOK-RIGHT* and *LOOK-LEFT* around ?PRODUCT-POSE."
  (setf *look-center* (cl-transforms-stamped:pose->pose-stamped "map" 0 ?product-pose))
  (setf *look-right* (get-right-pose ?product-pose))
  (setf *look-left* (get-left-pose ?product-pose)))

(defun offset-pose-stamped (pose offset)
  (cl-transforms-stamped:pose->pose-stamped
   "map" 0 (cl-transforms:transform->pose
            (cl-transforms:transform* (cl-transforms:pose->transform pose) offset))))

(defun get-left-pose (?product-pose)
  "The look target left of ?PRODUCT-POSE."
  (offset-pose-stamped ?product-pose *left-offset*))

(defun get-right-pose (?product-pose)
  "The look target right of ?PRODUCT-POSE."
  (offset-pose-stamped ?product-pose *right-offset*))

(defun get-product-type (?product-name)
  "The object type of the product ?PRODUCT-NAME from the knowledge base."
  (or (cut:var-value '?type (car (prolog `(and (is-of-type ,?product-name ?type)))))
      (error "GET-PRODUCT-TYPE: the knowledge base has no type for the product ~s." ?product-name)))

(defun look-at-product (?product-direction)
  "Look at ?PRODUCT-DIRECTION; when the neck cannot, back off and try again (twice)."
  (cpl:with-retry-counters ((error-counter 2))
    (cpl:with-failure-handling
        ((common-fail:ptu-goal-not-reached (e)
           (cpl:log-message :warn '(perception-failure)
                            "~a~%Looking at product went wrong...repositioning" e)
           (cpl:do-retry error-counter
             (move-to-location (get-robot-new-pose))
             (cpl:retry))
           (cpl:fail 'common-fail:looking-high-level-failure)))
      (perform (desig:an action (type looking)
                         (target (desig:a location (pose ?product-direction))))))))

(defun robot-current-pose ()
  (cl-transforms-stamped:pose->pose-stamped "map" 0 (btr:pose (btr:get-robot-object))))

(defun get-robot-new-pose ()
  "The robot's pose moved back by *ROBOTPOSEOFFSET*."
  (offset-pose-stamped (robot-current-pose) *robotPoseOffset*))

(defun calculate-robot-navigation-goal-towards-target (?location-pose)
  "The robot's current pose turned towards ?LOCATION-POSE."
  (calculate-pose-towards-target ?location-pose (robot-current-pose)))

(defun calculate-pose-towards-target (look-pose-stamped robot-pose-stamped)
  "ROBOT-POSE-STAMPED turned about z so that it faces LOOK-POSE-STAMPED (both fixed frame)."
  (let* ((robot->world (cl-transforms:transform-inv
                        (cl-transforms:pose->transform robot-pose-stamped)))
         (look (cl-transforms:transform-point robot->world
                                              (cl-transforms:origin look-pose-stamped)))
         (rotation-angle (atan (cl-transforms:y look) (cl-transforms:x look))))
    (cram-tf:rotate-pose robot-pose-stamped :z rotation-angle)))

(defun get-human-new-pose ()
  "Where the human stands when following the robot."
  (offset-pose-stamped (robot-current-pose) *humanPoseOffset*))

(defun move-human-to-location ()
  "Bring the human next to the robot."
  (setf (btr:pose (btr-utils:object-instance :my-human)) (get-human-new-pose)))
