;;;; Searching a product: where to stand to see a shelf, where to look, and the demo plan.

(in-package :cram-pepper-demo)

(defparameter *viewing-distance* 1.2d0
  "Metres in front of a shelf pose where the robot stands when no visibility costmap
solution is found.")

(defun facing-pose (target distance)
  "A base pose DISTANCE metres from TARGET (a pose), on the side of the open shelf front
(the side the robot is on), turned towards it."
  (let* ((robot (cl-transforms:origin (btr:pose (btr:get-robot-object))))
         (p (cl-transforms:origin target))
         (dx (- (cl-transforms:x robot) (cl-transforms:x p)))
         (dy (- (cl-transforms:y robot) (cl-transforms:y p)))
         ;; shelf 1 faces -x, shelf 2 faces +y: stand on the axis closest to the robot
         (direction (if (> (abs dx) (abs dy))
                        (cl-transforms:make-3d-vector (signum dx) 0 0)
                        (cl-transforms:make-3d-vector 0 (signum dy) 0)))
         (position (cl-transforms:v+ (cl-transforms:make-3d-vector (cl-transforms:x p)
                                                                   (cl-transforms:y p) 0)
                                     (cl-transforms:v* direction distance))))
    (cl-transforms-stamped:make-pose-stamped
     "map" 0d0 position
     (cl-transforms:axis-angle->quaternion
      (cl-transforms:make-3d-vector 0 0 1)
      (atan (- (cl-transforms:y direction)) (- (cl-transforms:x direction)))))))

(defun generate-robot-pose (?shelf-pose)
  "A base pose from which the robot sees ?SHELF-POSE: a VISIBLE-FOR location designator's
solution, or a pose in front of the shelf when it has none."
  (let* ((?product-pose-stamped (cl-transforms-stamped:pose->pose-stamped "map" 0 ?shelf-pose))
         (?product-location-designator (desig:a location (pose ?product-pose-stamped)))
         (?robot (rob-int:current-robot-name))
         (to-see-designator (desig:a location (visible-for ?robot)
                                     (location ?product-location-designator)
                                     (object (desig:an object (type :shelf))))))
    (handler-case (desig:reference to-see-designator)
      (error (e)
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
  (setf (btr:pose (btr:object btr:*current-bullet-world* :my-human)) (get-human-new-pose)))
