;;;; Plans over ROS (cram-ros-pms) against the simulated robot node: move-bottle end to end,
;;;; a perception miss, a blocked navigation goal and a lost master, under a private roscore.

(defpackage :cram-plans-tests-robot-ros
  (:use :cl :fiveam))

(in-package :cram-plans-tests-robot-ros)

(def-suite robot-ros :in cram-plans-tests:all
  :description "Robot process modules over ROS against tools/ros/sim_robot.py.")

(in-suite robot-ros)

(defvar *sim-launch-file* "launch/sim_robot.launch"
  "The launch file of the simulated robot (relative to the checkout).")

(defparameter *speed* 10 "Time factor of the simulated robot in these tests.")

(defun motion (type &rest properties)
  (desig:make-designator :motion (list* (list :type type) properties)))

(test process-modules-match-inside-with-real-robot-only
  "The robot process modules match the projection's motion types, and only run inside
WITH-REAL-ROBOT; without a node WITH-REAL-ROBOT says so."
  (let ((going (motion :going '(:pose ((0 0 0) (0 0 0 1))))))
    (is (null (cpm:matching-process-modules going)))
    (cpm:with-process-modules-running (cram-ros-pms:ros-navigation cram-ros-pms:ros-arms
                                       cram-ros-pms:ros-grippers cram-ros-pms:ros-perception)
      (is (equal '(cram-ros-pms:ros-navigation) (cpm:matching-process-modules going)))
      (is (equal '(cram-ros-pms:ros-arms) (cpm:matching-process-modules (motion :moving-tcp))))
      (is (equal '(cram-ros-pms:ros-grippers) (cpm:matching-process-modules (motion :gripping))))
      (is (equal '(cram-ros-pms:ros-perception) (cpm:matching-process-modules (motion :detecting))))))
  (is (eq (find-symbol "WITH-REAL-ROBOT" :pr2-pms) 'cram-ros-pms:with-real-robot))
  (unless (roslisp-utilities:ros-running-p)
    (signals cram-ros-pms:robot-connection-error (cram-ros-pms:with-real-robot 1))))

(defun counts ()
  (loop for k in '("move_base" "torso" "head" "left_arm" "right_arm" "left_gripper" "right_gripper"
                   "perception_requests")
        collect (cons k (cram-ros-pms::sim-count k))))

(defun count-delta (before after key)
  (- (cdr (assoc key after :test #'string=)) (cdr (assoc key before :test #'string=))))

(defun bottle-distance ()
  (let ((p (cram-ros-pms::sim-object-position "bottle-1")))
    (and p (cl-transforms:v-dist (apply #'cl-transforms:make-3d-vector p)
                                 (cl-transforms:origin btw-tut:*final-object-destination*)))))

(defun spawn-bottle-in-both-worlds (pose)
  (btw-tut::spawn-bottle pose)
  (let* ((bottle (btr:object btr:*current-bullet-world* 'btw-tut::bottle-1))
         (box (btr:bounding-box bottle)))
    (cram-ros-pms::spawn-sim-object "bottle-1" :bottle (btr:pose bottle)
                                    (list (cl-transforms:x box) (cl-transforms:y box) (cl-transforms:z box)))))

(defun hidden-message-stamp (name)
  "The stamp of the next perception message without the object NAME (5 s at most), or NIL."
  (let ((c cram-ros-pms::*live-connection*) (deadline (+ (get-internal-real-time) (* 5 internal-time-units-per-second))))
    (loop while (< (get-internal-real-time) deadline)
          do (let ((m (find-if-not (lambda (m) (some (lambda (marker) (string= (visualization_msgs-msg:text marker) name))
                                                     (second m)))
                                   (cram-ros-pms::connection-perception c))))
               (when m (return (first m))))
             (sleep 0.01))))

(defun run-move-bottle (pose)
  "Run BTW-TUT:MOVE-BOTTLE over ROS; values: the error text or NIL, the log, the motion labels
of the process modules that ran, seconds."
  (let ((log (make-string-output-stream))
        (labels '())
        (start (get-internal-real-time))
        (error nil))
    (let ((cpl:*log-stream* log)
          (hook (lambda (label) (push label labels))))
      ;; set globally: the plan's tasks run in threads of their own
      (push hook urdf-proj::*after-motion-hooks*)
      (unwind-protect
           (handler-case (cram-ros-pms:with-real-robot (btw-tut:move-bottle pose))
             (error (e) (setf error (princ-to-string e))))
        (setf urdf-proj::*after-motion-hooks* (remove hook urdf-proj::*after-motion-hooks*))))
    (values error (get-output-stream-string log) (reverse labels)
            (/ (- (get-internal-real-time) start) (float internal-time-units-per-second)))))

(test move-bottle-over-ros
  "move-bottle, the function projection runs, runs inside WITH-REAL-ROBOT against the simulated
robot at speed 10: every motion goes over ROS (the node's counts, no projection motion), the
bottle ends within 3 cm of the destination in the node's world; a perception miss is recovered
by a new look direction; a blocked navigation goal is NAVIGATION-POSE-UNREACHABLE; a lost master
is a ROBOT-CONNECTION-ERROR within a bounded time."
  ;; the random choices (IK restarts, costmap samples) start where a fresh image starts, so the
  ;; run does not depend on what the suites before it drew
  (urdf-proj:reset-ik-random-state)
  (costmap:seed-costmaps 1)
  (cram-ros-pms::start-private-ros)
  (unwind-protect
       (progn
         (cram-ros-pms::start-sim-robot :speed *speed* :launch-file *sim-launch-file*)
         (roslisp-utilities:startup-ros :publish-rate nil)
         ;; 1. end to end
         (spawn-bottle-in-both-worlds btw-tut:*bottle-pose-in-view*)
         (let ((before (counts)))
           (multiple-value-bind (error log labels seconds) (run-move-bottle btw-tut:*bottle-pose-in-view*)
             (declare (ignore log))
             (is (null error) "move-bottle over ROS failed: ~a" error)
             (let ((after (counts)) (d (bottle-distance)))
               (is (and d (<= d 0.03)) "bottle ~a m from the destination in the simulated world" d)
               (is (>= (count-delta before after "move_base") 2))
               (is (>= (count-delta before after "torso") 1))
               (is (>= (count-delta before after "head") 1))
               (is (>= (+ (count-delta before after "left_arm") (count-delta before after "right_arm")) 4))
               (is (>= (+ (count-delta before after "left_gripper") (count-delta before after "right_gripper")) 2))
               (is (>= (count-delta before after "perception_requests") 1))
               ;; the plan's motions all ran on the robot process modules, none in projection
               (is (member "drive" labels :test #'string=))
               (is (member "move-tcp" labels :test #'string=))
               (is (notany (lambda (l) (member l '("going" "moving-tcp" "detecting" "looking") :test #'string=))
                           labels)
                   "projection motions ran: ~a" labels)
               (format t "~&move-bottle over ROS at speed ~a: ~,1f s, counts ~a~%" *speed* seconds
                       (mapcar (lambda (c) (list (car c) (count-delta before after (car c)))) after)))))
         ;; 2. a perception miss: the bottle left out of the first detection's message
         (spawn-bottle-in-both-worlds btw-tut:*bottle-pose-in-view*)
         (cram-ros-pms::inject-fault "{\"clear\": true}")
         (let ((injected nil))
           ;; set globally: detecting runs in a task thread of its own
           (setf cram-ros-pms::*before-detect-hooks*
                 (list (lambda ()
                         (unless injected
                           (setf injected t)
                           (cram-ros-pms::inject-fault
                            "{\"hide_object\": {\"name\": \"bottle-1\", \"count\": 1}}")
                           ;; the detection takes the message the node left the bottle out of
                           (hidden-message-stamp "bottle-1")))))
           (multiple-value-bind (error log)
               (unwind-protect (run-move-bottle btw-tut:*bottle-pose-in-view*)
                 (setf cram-ros-pms::*before-detect-hooks* '()))
             (is (null error) "move-bottle with a perception miss failed: ~a" error)
             (is (search "Turning head." log) "no new look direction in the log")
             (let ((d (bottle-distance)))
               ;; after the miss the plan looks elsewhere and may take another arm and grasp; the
               ;; simulated robot lets go where the tool frame is once the arm has arrived
               (is (and d (<= d 0.03)) "bottle ~a m from the destination after the miss" d))))
         ;; 3. a blocked navigation goal surfaces as the typed failure
         (cram-ros-pms::inject-fault "{\"block_navigation\": 1}")
         (sleep 0.1)
         (let ((?pose btw-tut::*base-pose-near-table*))
           (signals common-fail:navigation-pose-unreachable
             (cram-ros-pms:with-real-robot
               (exe:perform (desig:a motion (type going) (pose ?pose))))))
         ;; 3b. a refused joint command: the joints stand still away from the goal, which is the
         ;; typed failure naming the joint, what it wanted and where it stopped
         (cram-ros-pms::inject-fault "{\"reject_joint_goals\": 1}")
         (sleep 0.1)
         (let ((failure nil))
           (handler-case (cram-ros-pms:with-real-robot
                           (let ((?angle (if (> (gethash "torso_lift_joint" (cram-ros-pms::robot-joint-positions))
                                                0.2)
                                             0.1 0.25)))
                             (exe:perform (desig:a motion (type moving-torso) (joint-angle ?angle)))))
             (common-fail:torso-goal-not-reached (e) (setf failure e)))
           (is (typep failure 'common-fail:torso-goal-not-reached))
           (let ((text (princ-to-string failure)))
             (is (and (search "joints stopped for" text) (search "torso_lift_joint wanted" text))
                 "the failure does not say the joints stopped: ~a" text)))
         ;; 4. the master is lost: a clear error naming it, in bounded time
         (let ((start (get-internal-real-time)) (condition nil))
           (handler-case
               (cram-ros-pms:with-real-robot
                 (cram-ros-pms::kill-private-master)
                 (exe:perform (desig:a motion (type moving-torso) (joint-angle 0.1)))
                 (exe:perform (desig:a motion (type moving-torso) (joint-angle 0.3))))
             (cram-ros-pms:robot-connection-error (e) (setf condition e)))
           (let ((seconds (/ (- (get-internal-real-time) start) (float internal-time-units-per-second))))
             (is (typep condition 'cram-ros-pms:robot-connection-error))
             (is (and condition (search "master" (princ-to-string condition))) "~a" condition)
             (is (< seconds 15) "the lost master took ~,1f s to notice" seconds))))
    (ignore-errors (cram-ros-pms::call-with-deadline 5 "shutdown" "shutting the node down"
                                                     #'roslisp-utilities:shutdown-ros))
    (cram-ros-pms::stop-private-ros)))
