;;;; tools/cram-plans-run --demo move-bottle --robot ros [--speed S]: the same move-bottle plan
;;;; as in projection, run inside PR2-PMS:WITH-REAL-ROBOT against the simulated robot node
;;;; (launch/sim_robot.launch) under a private roscore. Loaded by runner.lisp on demand.

(in-package :cram-plans-demo)

(handler-bind ((warning #'muffle-warning))
  (asdf:load-system "cram-plans/cram-ros-pms"))

(defun robot-bottle-spawn (pose)
  "Put BOTTLE-1 at POSE in the belief state as move-bottle's SPAWN-BOTTLE does (it settles),
and at that settled pose with the belief bottle's bounding box in the simulated robot's world."
  (btw-tut::spawn-bottle pose)
  (let* ((bottle (btr:object btr:*current-bullet-world* 'btw-tut::bottle-1))
         (box (btr:bounding-box bottle)))
    (cram-ros-pms::spawn-sim-object "bottle-1" :bottle (btr:pose bottle)
                                    (list (cl-transforms:x box) (cl-transforms:y box) (cl-transforms:z box)))))

(defun run-move-bottle-over-ros (&key (speed 1) (pose btw-tut:*bottle-pose-in-view*)
                                      (launch-file "launch/sim_robot.launch")
                                      (before-plan nil))
  "Start a private roscore and LAUNCH-FILE (the simulated robot at SPEED), build the belief
state from the parameter server, put the bottle at POSE in both worlds, call BEFORE-PLAN (a
function or NIL) and run BTW-TUT:MOVE-BOTTLE inside WITH-REAL-ROBOT. Stops everything it started.
Returns a plist: :success (the bottle ends within *TOLERANCE* of the destination in the simulated
robot's world), :distance, :position, :seconds (the plan), :counts, :error."
  (cram-ros-pms::start-private-ros)
  (unwind-protect
       (let ((error nil) (seconds nil))
         (cram-ros-pms::start-sim-robot :speed speed :launch-file launch-file)
         (roslisp-utilities:startup-ros :publish-rate nil)
         (robot-bottle-spawn pose)
         (when before-plan (funcall before-plan))
         (let ((start (get-internal-real-time)))
           (handler-case (cram-ros-pms:with-real-robot (btw-tut:move-bottle pose))
             (error (e) (setf error (princ-to-string e))))
           (setf seconds (float (/ (- (get-internal-real-time) start) internal-time-units-per-second) 1d0)))
         (let* ((position (ignore-errors (cram-ros-pms::sim-object-position "bottle-1")))
                (distance (and position
                               (cl-transforms:v-dist (apply #'cl-transforms:make-3d-vector position)
                                                     (cl-transforms:origin btw-tut:*final-object-destination*)))))
           (list :success (and (null error) distance (<= distance *tolerance*))
                 :distance distance :position position :seconds seconds :error error
                 :counts (ignore-errors
                          (loop for k in '("move_base" "torso" "head" "left_arm" "right_arm"
                                           "left_gripper" "right_gripper" "perception_requests")
                                collect (cons k (cram-ros-pms::sim-count k)))))))
    (ignore-errors (roslisp-utilities:shutdown-ros))
    (cram-ros-pms::stop-private-ros)))

(defun run-robot-demo (options)
  "The --robot ros branch of the command line: move-bottle over ROS; prints SUCCESS or FAILURE
and returns true on success."
  (unless (string= (getf options :demo) "move-bottle")
    (usage-fail "--robot ros runs only --demo move-bottle, got --demo ~s" (getf options :demo)))
  (unless (string= (getf options :robot) "ros")
    (usage-fail "--robot ~s is unknown, expected ros" (getf options :robot)))
  (seed-everything (getf options :seed))
  (let* ((log (if (getf options :quiet) (make-broadcast-stream) *standard-output*))
         (result (let ((cpl:*log-stream* log))
                   (run-move-bottle-over-ros :speed (or (getf options :speed) 1)
                                             :pose (or (getf options :pose) btw-tut:*bottle-pose-in-view*)))))
    (format t "~&~:[FAILURE~;SUCCESS~]: bottle ~@[~,3f m~] from the destination in the simulated ~
               robot's world (plan ~,1f s over ROS)~@[; error: ~a~]~%counts: ~{~a~^ ~}~%"
            (getf result :success) (getf result :distance) (or (getf result :seconds) 0)
            (getf result :error)
            (mapcar (lambda (c) (format nil "~a=~a" (car c) (cdr c))) (getf result :counts)))
    (getf result :success)))
