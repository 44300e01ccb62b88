;;;; Tests of the Pepper description and of costmap metadata with two robots loaded.

(in-package :cram-robots-tests)

(in-suite robots)

;;; Pepper, as the shopping-assistant tutorial writes it

(test pepper-general-knowledge
  (let ((odom (query-values '?f `(rob-int:robot-odom-frame ,*pepper* ?f)))
        (base (query-values '?f `(rob-int:robot-base-frame ,*pepper* ?f)))
        (torso (first (cut:force-ll
                       (prolog:prolog `(rob-int:robot-torso-link-joint ,*pepper* ?link ?joint)))))
        (arms (query-values '?a `(rob-int:arm ,*pepper* ?a)))
        (camera (query-values '?f `(rob-int:camera-frame ,*pepper* ?f)))
        (low (query-value '?h `(rob-int:camera-minimal-height ,*pepper* ?h)))
        (high (query-value '?h `(rob-int:camera-maximal-height ,*pepper* ?h))))
    (is (equal '("odom") odom))
    (is (equal '("base_link") base))
    (is (equal "torse" (value-of :link torso)))
    (is (equal "base_link_fixedjoint" (value-of :joint torso)))
    (is (equal '(:left :right) arms))
    (is (equal '("CameraDepth_optical_frame") camera))
    (is (= 1.00 low))
    (is (= 1.10 high))))

(test pepper-arms
  (let ((left (query-values '?j `(rob-int:arm-joints ,*pepper* :left ?j)))
        (right-links (query-value '?l `(rob-int:arm-links ,*pepper* :right ?l)))
        (ee (query-values '?l `(rob-int:end-effector-link ,*pepper* ?arm ?l)))
        (tool (query-values '?f `(rob-int:robot-tool-frame ,*pepper* ?arm ?f)))
        (grippers (query-values '?j `(rob-int:gripper-joint ,*pepper* ?arm ?j)))
        (tip (holds `(rob-int:gripper-link ,*pepper* :left "left_gripper_tip_frame")))
        (thumb (holds `(rob-int:gripper-link ,*pepper* :left "LThumb1_link")))
        (unbound (holds `(rob-int:gripper-link ,*pepper* :left ?link)))
        (multiplier (query-values '?m `(rob-int:gripper-meter-to-joint-multiplier ,*pepper* ?m)))
        (standard (query-value '?t `(rob-int:standard-to-particular-gripper-transform
                                     ,*pepper* ?t))))
    (is (equal '(("LShoulderPitch" "LShoulderRoll" "LElbowYaw" "LElbowRoll" "LWristYaw")) left))
    (is (equal '("RShoulder" "RBicep" "RElbow" "RForeArm" "r_wrist") right-links))
    (is (equal '("LThumb1_link" "RThumb1_link") ee))
    (is (equal '("LThumb1" "RThumb1") tool))
    (is (equal '("left_gripper_joint" "right_gripper_joint") grippers))
    (is-true tip)
    (is-false thumb)
    (is-false unbound)
    (is (equal '(1.0) multiplier))
    (is (typep standard 'cl-transforms:transform))
    (is (zerop (cl-transforms:v-norm (cl-transforms:translation standard))))))

(test pepper-arm-configurations
  (let ((left-park (query-values '?s `(rob-int:robot-joint-states ,*pepper* :arm :left :park ?s)))
        (right-park (rob-int:get-robot-joint-states *pepper* :arm :right :park))
        (left-point (rob-int:get-robot-joint-states *pepper* :arm :left :point))
        (right-point (rob-int:get-robot-joint-states *pepper* :arm :right :point))
        (ahead (rob-int:get-robot-joint-states *pepper* :arm :right :point-ahead))
        (left-ahead (query-values '?s `(rob-int:robot-joint-states ,*pepper* :arm :left
                                                                    :point-ahead ?s))))
    (is (equal '((("LShoulderPitch" 1.08) ("LShoulderRoll" 0.51) ("LElbowYaw" -0.15)
                  ("LElbowRoll" -0.79) ("LWristYaw" 0.00)))
               left-park))
    (is (equal '(("RShoulderPitch" 1.08) ("RShoulderRoll" -0.53) ("RElbowYaw" 0.0)
                 ("RElbowRoll" 0.79) ("RWristYaw" 0.0))
               right-park))
    (is (equal '(("LShoulderPitch" -0.46) ("LShoulderRoll" 0.99) ("LElbowYaw" -1.18)
                 ("LElbowRoll" -0.01) ("LWristYaw" 0.00))
               left-point))
    (is (equal '(("RShoulderPitch" -0.41) ("RShoulderRoll" -1.00) ("RElbowYaw" 0.50)
                 ("RElbowRoll" 0.01) ("RWristYaw" 0.91))
               right-point))
    (is (equal '(("RShoulderPitch" -0.13) ("RShoulderRoll" -0.37) ("RElbowYaw" 0.46)
                 ("RElbowRoll" 0.69) ("RWristYaw" 1.82))
               ahead))
    (is (null left-ahead))
    (is (equal (rob-int:get-arm-joints *pepper* :right) (mapcar #'first right-park)))))

(test pepper-neck
  (let ((links (query-values '?l `(rob-int:robot-neck-links ,*pepper* . ?l)))
        (joints (query-values '?j `(rob-int:robot-neck-joints ,*pepper* . ?j)))
        (down (query-value '?s `(rob-int:robot-joint-states ,*pepper* :neck nil :down ?s)))
        (down-left (query-value '?s `(rob-int:robot-joint-states ,*pepper* :neck :any
                                                                  :down-left ?s)))
        (forward (query-value '?s `(rob-int:robot-joint-states ,*pepper* :neck nil :forward ?s)))
        (away (query-value '?s `(rob-int:robot-joint-states ,*pepper* :neck nil :away ?s)))
        (names (query-values '?n `(rob-int:robot-joint-states ,*pepper* :neck nil ?n ?_))))
    (is (equal '(("Neck" "Head")) links))
    (is (equal '(("HeadYaw" "HeadPitch")) joints))
    (is (equal '(("HeadYaw" 0.00) ("HeadPitch" 0.62)) down))
    (is (equal '(("HeadYaw" 0.86) ("HeadPitch" 0.00)) down-left))
    (is (equal '(("HeadYaw" 0.00) ("HeadPitch" -0.00)) forward))
    (is (equal forward away))
    (is (equal '(:away :forward :down :down-left) names))))

(test pepper-facts-do-not-leak-into-pr2
  (let ((pr2-multiplier (query-values '?m '(rob-int:gripper-meter-to-joint-multiplier :pr2 ?m)))
        (pr2-neck-states (query-values '?n '(rob-int:robot-joint-states :pr2 :neck ?id ?n ?_)))
        (pr2-neck-joints (mapcar #'first
                                 (reduce #'append
                                         (query-values '?s '(rob-int:robot-joint-states
                                                             :pr2 :neck ?id ?_ ?s)))))
        (pepper-hand (query-values '?l `(rob-int:hand-links ,*pepper* :left ?l))))
    (is (equal '(5.0) pr2-multiplier))
    ;; the PR2's own neck state only, on the PR2's neck joints: none of Pepper's
    (is (equal '(:forward) pr2-neck-states))
    (is (equal '("head_pan_joint" "head_tilt_joint") pr2-neck-joints))
    (is (null pepper-hand))))

;;; Costmap metadata with both descriptions loaded

(defparameter *metadata-queries*
  '((size (costmap:costmap-size ?a ?b))
    (origin (costmap:costmap-origin ?a ?b))
    (resolution (costmap:costmap-resolution ?a))
    (padding (costmap:costmap-padding ?a))
    (manipulation-padding (costmap:costmap-manipulation-padding ?a))
    (in-reach (costmap:costmap-in-reach-distance ?a))
    (reach-minimal (costmap:costmap-reach-minimal-distance ?a))
    (visibility (costmap:visibility-costmap-size ?a))
    (orientation-samples (costmap:orientation-samples ?a))
    (orientation-step (costmap:orientation-sample-step ?a)))
  "One query per metadata predicate, named.")

(defun metadata-solutions (name)
  "All solutions of the metadata query NAME as lists of the values of ?A and ?B."
  (let ((query (second (assoc name *metadata-queries*))))
    (mapcar (lambda (bindings)
              (remove nil (list (cut:var-value '?a bindings)
                                (let ((b (cut:var-value '?b bindings)))
                                  (if (cut:is-var b) nil b)))))
            (cut:force-ll (prolog:prolog query)))))

(defun first-metadata (name)
  "The first solution of the metadata query NAME."
  (first (metadata-solutions name)))

(test costmap-metadata-follows-pepper-when-pepper-is-current
  (let ((values (with-robot (*pepper*)
                  (mapcar (lambda (entry) (metadata-solutions (first entry)))
                          *metadata-queries*))))
    ;; Only the Pepper group answers: one solution each, the tutorial's values.
    (is (equal '(((12 12)) ((-6 -6)) ((0.04)) ((0.3)) ((0.4)) ((0.7)) ((0.2)) ((2)) ((2)) ((0.1)))
               values))))

(test costmap-metadata-follows-the-pr2-when-the-pr2-is-current
  (with-robot (:pr2)
    (let ((in-reach (metadata-solutions 'in-reach))
          (samples (metadata-solutions 'orientation-samples))
          (padding (first-metadata 'padding))
          (manipulation (first-metadata 'manipulation-padding))
          (minimal (first-metadata 'reach-minimal))
          (visibility (first-metadata 'visibility))
          (size (first-metadata 'size))
          (origin (first-metadata 'origin))
          (resolution (first-metadata 'resolution)))
      (is (equal '(1.05) (first in-reach)) "the PR2's reach comes first")
      (is (member '(0.7) in-reach :test #'equal) "unkeyed groups still answer after it")
      (is (equal '(1) (first samples)))
      (is (equal '(0.3) padding))
      (is (equal '(0.4) manipulation))
      (is (equal '(0.2) minimal))
      (is (equal '(2) visibility))
      (is (equal '(12 12) size))
      (is (equal '(-6 -6) origin))
      (is (equal '(0.04) resolution)))))

(test costmap-metadata-keyed-by-an-unknown-robot-is-not-used
  (let ((as-other (with-robot (:no-such-robot) (metadata-solutions 'in-reach)))
        (without-robot (with-robot (nil) (metadata-solutions 'in-reach))))
    (is (equal '((0.7)) as-other))
    (is (member '(1.05) without-robot :test #'equal))
    (is (member '(0.7) without-robot :test #'equal))))

(test costmap-metadata-groups-of-the-user-extend-the-predicates
  (unwind-protect
       (progn
         (eval '(prolog:def-fact-group robots-test-costmap-metadata
                    (costmap:costmap-padding costmap:robot-costmap-metadata)
                  (prolog:<- (costmap:costmap-padding 0.55))
                  (prolog:<- (costmap:robot-costmap-metadata
                              :robots-test-bot (costmap:costmap-padding 0.9)))))
         (let ((as-test-bot (with-robot (:robots-test-bot) (metadata-solutions 'padding)))
               (as-pepper (with-robot (*pepper*) (metadata-solutions 'padding)))
               (as-pr2 (with-robot (:pr2) (metadata-solutions 'padding))))
           (is (equal '(0.9) (first as-test-bot)))
           (is (member '(0.55) as-test-bot :test #'equal))
           (is (not (member '(0.9) as-pepper :test #'equal)))
           (is (equal '((0.3) (0.55)) (remove-duplicates as-pepper :test #'equal)))
           (is (equal '(0.3) (first as-pr2)))))
    (prolog:remove-fact-group 'robots-test-costmap-metadata)))
