;;;; Environment manipulation with a ROS node running: the kitchen's joint states go out on
;;;; kitchen/cram_joint_states after a container event (a private roscore, no launch file).

(in-package :cram-plans-tests-ros)

(fiveam:in-suite cram-plans-tests-environment-manipulation::environment-manipulation)

(fiveam:test kitchen-joint-states-on-ros
  (let ((old-world btr:*current-bullet-world*) (left :not-run))
    (unwind-protect
         (setf left
               (call-with-private-ros
                (lambda ()
                  (let ((roslisp-utilities:*ros-init-functions* '(btw-tut:init-projection)))
                    (roslisp-utilities:startup-ros :anonymous t))
                  (fiveam:is-true (roslisp-utilities:ros-running-p))
                  (let ((states (subscribe-collecting "/kitchen/cram_joint_states" "sensor_msgs/JointState")))
                    (sleep 0.5)         ; the subscription connects
                    (coe:on-event (make-instance 'cpoe:container-opening-event
                                                 :environment-name :iai-kitchen
                                                 :joint-name "sink_area_left_upper_drawer_main_joint"
                                                 :distance 0.3))
                    (fiveam:is-true
                     (wait-until 5 (lambda ()
                                     (some (lambda (m)
                                             (let ((i (position "sink_area_left_upper_drawer_main_joint"
                                                                (sensor_msgs-msg:name m) :test #'string=)))
                                               (and i (< (abs (- 0.3d0 (aref (sensor_msgs-msg:position m) i)))
                                                         1d-6))))
                                           (funcall states))))
                     "no joint state with the opened drawer arrived"))
                  (fiveam:is-true (roslisp-utilities:shutdown-ros)))))
      (setf btr:*current-bullet-world* old-world))
    (fiveam:is (null left) "processes left behind: ~a" left)))
