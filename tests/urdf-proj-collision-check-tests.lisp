;;;; Tests of the yes/no collision check of the simulated robot (URDF-PROJ:ROBOT-COLLIDES-P,
;;;; the native check that stops at the first contact that counts) against the list of what the
;;;; robot touches (URDF-PROJ:ROBOT-COLLISIONS), and of MOVE-TCP giving up a goal whose hand
;;;; touches the world.

(in-package :cram-plans-tests.urdf-proj)

(in-suite urdf-proj)

(defun random-between (lo hi state)
  (+ lo (random (- hi lo) state)))

(defun randomize-arms (state)
  "Put both arms of the PR2 and its torso into random configurations within their limits."
  (let ((robot (robot)))
    (btr:set-robot-state-from-joints
     (loop for joint in (append (rob-int:get-arm-joints :pr2 :left) (rob-int:get-arm-joints :pr2 :right)
                                '("torso_lift_joint"))
           collect (multiple-value-bind (lo hi) (btr:joint-limits robot joint)
                     (list joint (random-between (max (or lo -3d0) -3d0) (min (or hi 3d0) 3d0) state))))
     robot)))

(test the-first-contact-check-agrees-with-the-list-of-contacts
  (with-kitchen
    (let* ((state (sb-ext:seed-random-state 17))
           (robot (robot))
           (left-hand (urdf-proj::hand-links :left robot))
           (right-arm (append (urdf-proj::hand-links :right robot) (rob-int:get-arm-links :pr2 :right)))
           (allowed-sets (list '()
                               '(("r_gripper_palm_link" t))
                               '((t :iai-kitchen))
                               '((t bottle-1))
                               '(("l_forearm_link" (:iai-kitchen "sink_area_surface")))))
           (colliding 0) (free 0) (disagree '()))
      (dotimes (i 300)
        (setf (btr:pose robot)
              (cl-transforms:make-pose
               (cl-transforms:make-3d-vector (random-between -2.4d0 -1.3d0 state)
                                             (random-between -0.6d0 0.6d0 state) 0)
               (cl-transforms:axis-angle->quaternion (cl-transforms:make-3d-vector 0 0 1)
                                                     (random-between (- pi) pi state))))
        (randomize-arms state)
        (let* ((ignore (nth (random 3 state) (list nil left-hand right-arm)))
               (urdf-proj:*sweep-allowed-contacts* (nth (random (length allowed-sets) state) allowed-sets))
               (listed (not (null (urdf-proj:robot-collisions :ignore-links ignore))))
               (found (urdf-proj:robot-collides-p :ignore-links ignore)))
          (if listed (incf colliding) (incf free))
          (unless (eq listed found)
            (push (list i ignore urdf-proj:*sweep-allowed-contacts* (urdf-proj:robot-collisions :ignore-links ignore))
                  disagree))))
      (is (null disagree) "the checks disagree in ~d of 300 states: ~s" (length disagree)
          (subseq disagree 0 (min 3 (length disagree))))
      (is (> colliding 30) "only ~d colliding states" colliding)
      (is (> free 30) "only ~d free states" free))))

(test the-first-contact-check-counts-what-a-carried-object-touches
  (with-kitchen
    (let ((robot (robot)))
      (urdf-proj:with-simulated-robot
        (urdf-proj:move-joints :park :park)
        (urdf-proj:drive *grasp-base-pose*))
      (is (not (urdf-proj:robot-collides-p)))
      ;; the bottle held by the right hand, pushed into the table top
      (btr:attach-object robot (btr:object btr:*current-bullet-world* 'bottle-1)
                         :link "r_gripper_tool_frame")
      (setf (btr:pose (btr:object btr:*current-bullet-world* 'bottle-1))
            (cl-transforms:make-pose (cl-transforms:make-3d-vector -2.0 -0.9 0.80)
                                     (cl-transforms:make-identity-rotation)))
      (is (equal (urdf-proj:robot-collisions) (list :iai-kitchen)))
      (is (urdf-proj:robot-collides-p))
      (let ((urdf-proj:*sweep-allowed-contacts* '((bottle-1 :iai-kitchen))))
        (is (null (urdf-proj:robot-collisions)))
        (is (not (urdf-proj:robot-collides-p)))))))

(test the-first-contact-query-names-bad-input
  (with-kitchen
    (let ((w (btr::world-handle btr:*current-bullet-world*))
          (robot (btr:object-handle (robot)))
          (bottle (btr:object-handle (btr:object btr:*current-bullet-world* 'bottle-1))))
      (is (null (cram-native:object-first-contact w robot :except (list bottle)
                                                  :allowed '((:any :any :any)))))
      (signals error (cram-native:object-first-contact w robot :allowed '((1 2))))
      (signals error (cram-native:object-first-contact w robot :skip-links '("base_link")))
      (let ((message (handler-case (progn (cram-native:object-first-contact w bottle) nil)
                       (error (e) (princ-to-string e)))))
        (is (search "articulated" message) "~s" message)))))

(test the-first-contact-query-packs-long-lists
  ;; the robot standing inside the table: what is left out, whether given first or after 2 000
  ;; triples that cover nothing (past what goes on the stack)
  (with-kitchen
    (let* ((w (btr::world-handle btr:*current-bullet-world*))
           (robot (btr:object-handle (robot)))
           (kitchen (btr:object-handle (btr:object btr:*current-bullet-world* :iai-kitchen)))
           (bottle (btr:object-handle (btr:object btr:*current-bullet-world* 'bottle-1)))
           (filler (loop repeat 2000 collect (list 0 -5 0))))
      (setf (btr:pose (robot)) (cl-transforms:make-pose (cl-transforms:make-3d-vector -2.0 -0.9 0)
                                                        (cl-transforms:make-identity-rotation)))
      (let ((contact (cram-native:object-first-contact w robot :except (list bottle))))
        (is (eql kitchen (third contact)) "~s" contact)
        (dolist (allowed (list '((:any :any :any)) (append filler '((:any :any :any)))
                               `((:any ,kitchen :any) (:any ,bottle :any))))
          (is (null (cram-native:object-first-contact w robot :allowed allowed))))
        (is (eql kitchen (third (cram-native:object-first-contact w robot :except (list bottle)
                                                                          :allowed filler))))
        (is (null (cram-native:object-first-contact w robot :except (list bottle kitchen)
                                                            :allowed filler)))
        (signals error (cram-native:object-first-contact w robot :except '(:iai-kitchen)))))))

(defun stand-at-the-grasp-pose ()
  "Park the arms, drive the robot to *GRASP-BASE-POSE* and raise its torso to 0.3."
  (urdf-proj:with-simulated-robot
    (urdf-proj:move-joints :park :park)
    (urdf-proj:drive *grasp-base-pose*)
    (urdf-proj:move-torso 0.3)))

(defun solves-reaching (goal &optional (arm :left))
  "The number of IK solutions MOVE-TCP tried to bring the tool frame of ARM to GOAL, and
whether it failed (a low-level manipulation failure)."
  (calls-during 'urdf-proj:solve-ik
                (lambda ()
                  (handler-case (progn (urdf-proj:with-simulated-robot
                                         (if (eq arm :left)
                                             (urdf-proj:move-tcp goal nil)
                                             (urdf-proj:move-tcp nil goal)))
                                       nil)
                    (common-fail:manipulation-low-level-failure () t)))))

(test a-tool-goal-whose-hand-touches-the-world-is-given-up-at-once
  (with-kitchen
    (stand-at-the-grasp-pose)
    ;; the gripper half inside the table top: no base offset or torso height frees it
    (multiple-value-bind (solves failed) (solves-reaching (ps "map" -2.0 -0.80 0.72 (/ pi -2)) :right)
      (is (eq t failed))
      (is (<= 1 solves 12) "~d IK solutions were tried for a hand inside the table" solves))))

(defun deepest-hand-contact (robot links)
  "The smallest contact distance (metres, negative: into it) of ROBOT's LINKS with the kitchen."
  (let ((world btr:*current-bullet-world*))
    (loop for (nil la other nil d) in (cram-native:object-contacts (btr::world-handle world)
                                                                   (btr:object-handle robot))
          when (and (member (btr::link-name-of robot la) links :test #'string=)
                    (eq (btr::object-by-handle world other) (btr:object world :iai-kitchen)))
            minimize d)))

(defun hand-sunk-goal (robot depth)
  "A tool goal over the table (yaw -pi/2, as in the test above) lowered in 0.5 mm steps until
the left hand's links reach at least DEPTH metres into the kitchen with the hand there
\(reached with collisions allowed), with the arms parked again afterwards: the goal and how
deep they reach."
  (let ((links (urdf-proj::hand-links :left robot)))
    (unwind-protect
         (loop for z from 0.80d0 downto 0.70d0 by 0.0005d0
               for goal = (ps "map" -2.0 -0.80 z (/ pi -2))
               do (urdf-proj:with-simulated-robot
                    (urdf-proj:move-tcp goal nil :collision-mode :allow-all))
                  (let ((d (deepest-hand-contact robot links)))
                    (when (<= d (- depth))
                      (return (values goal d)))))
      (urdf-proj:with-simulated-robot (urdf-proj:move-joints :park :park)))))

(test a-tool-goal-whose-hand-sinks-beyond-what-the-ik-can-move-it-is-given-up-at-once
  ;; A finger a few millimetres into the table: less than the fixed centimetre of old, more
  ;; than another IK solution within the tolerances can move it.
  (with-kitchen
    (let ((robot (robot)))
      (stand-at-the-grasp-pose)
      (let* ((chain (urdf-proj::arm-ik-chain :left robot))
             (slacks (mapcar (lambda (l) (urdf-proj::goal-bound-slack robot chain l 0d0 0d0))
                             (urdf-proj::goal-bound-links chain robot))))
        ;; the tolerances' 1 mm plus 0.01 rad over the hand's reach from the wrist
        (is (every (lambda (s) (< 0.0009d0 s 0.0045d0)) slacks) "slacks ~s" slacks))
      (multiple-value-bind (goal depth) (hand-sunk-goal robot 0.006d0)
        (is (not (null goal)))
        (is (< -0.0095d0 depth) "the hand reaches ~,4f m into the table" depth)
        (multiple-value-bind (solves failed) (solves-reaching goal)
          (is (eq t failed))
          (is (<= 1 solves 12) "~d IK solutions were tried for a hand ~,4f m inside the table"
              solves depth))))))

(test a-tool-goal-whose-hand-only-touches-the-world-is-searched-on
  ;; Less deep than another IK solution may move the hand: other candidates are tried.
  (with-kitchen
    (let ((robot (robot)))
      (stand-at-the-grasp-pose)
      (multiple-value-bind (goal depth) (hand-sunk-goal robot 0.0001d0)
        (is (not (null goal)))
        (is (< -0.001d0 depth) "the hand reaches ~,4f m into the table" depth)
        (let ((solves (solves-reaching goal)))
          (is (> solves 12) "only ~d IK solutions were tried for a hand touching the table"
              solves))))))
