;;;; Tests of cram-native's inverse kinematics on the PR2 arms: success rate on random reachable
;;;; poses, answers checked with the forward kinematics, limits, determinism, seeds.

(in-package :cram-native-tests)

(in-suite native)

(defparameter *ik-pr2-urdf* (asdf:system-relative-pathname "cram-plans/cram-native" "robots/pr2/pr2.urdf"))

(defun pose-errors (a b)
  "Position (m) and rotation (rad) distance between the poses (vectors of 7) A and B."
  (values (sqrt (loop for i below 3 sum (expt (- (aref a i) (aref b i)) 2)))
          (* 2 (acos (min 1d0 (abs (loop for i from 3 below 7 sum (* (aref a i) (aref b i)))))))))

(defun random-q (lo hi state)
  "Joint values drawn uniformly within the limits LO .. HI."
  (map '(simple-array double-float (*)) (lambda (a b) (+ a (random (- b a) state))) lo hi))

(defmacro with-pr2-chain ((chain tip) &body body)
  "Run BODY with CHAIN bound to the PR2 chain torso_lift_link -> TIP (skipped without a model)."
  (let ((w (gensym "W")) (r (gensym "R")))
    `(if (not (probe-file *ik-pr2-urdf*))
         (skip "no PR2 model at ~a" *ik-pr2-urdf*)
         (progn
           (with-world (,w)
             (let* ((,r (add-urdf ,w (uiop:read-file-string *ik-pr2-urdf*)))
                    (,chain (make-chain ,w ,r "torso_lift_link" ,tip)))
               (unwind-protect (progn ,@body)
                 (destroy-chain ,chain))))))))

(defun ik-round-trips (chain n state)
  "Solve N random reachable poses of CHAIN from random seeds.  Returns the number solved and
a list of problems (answers off the target, outside the limits, or with wrong reported errors)."
  (multiple-value-bind (lo hi) (chain-limits chain)
    (let ((solved 0) (problems '()))
      (dotimes (k n)
        (let* ((target (chain-fk chain (random-q lo hi state)))
               (seed (random-q lo hi state)))
          (multiple-value-bind (q err) (chain-ik chain target :seed seed :random-seed (1+ k))
            (when q
              (incf solved)
              (multiple-value-bind (pe re) (pose-errors (chain-fk chain q) target)
                (unless (and (<= pe 1d-3) (<= re 1d-2))
                  (push (list :off-target k pe re) problems))
                (unless (and (approx pe (aref err 0) 1d-7) (approx re (aref err 1) 1d-6))
                  (push (list :reported-errors k pe re err) problems)))
              (unless (every (lambda (x a b) (<= (- a 1d-12) x (+ b 1d-12))) q lo hi)
                (push (list :outside-limits k q) problems))))))
      (values solved problems))))

(test ik-pr2-arms-random-poses
  (dolist (tip '("l_wrist_roll_link" "r_wrist_roll_link" "l_gripper_tool_frame"))
    (with-pr2-chain (c tip)
      (multiple-value-bind (solved problems) (ik-round-trips c 200 (sb-ext:seed-random-state 11))
        (is (>= solved 198) "~a: only ~d of 200 reachable poses solved" tip solved)
        (is (null problems) "~a: ~s" tip problems)))))

(test ik-deterministic-and-seeded
  (with-pr2-chain (c "r_wrist_roll_link")
    (multiple-value-bind (lo hi) (chain-limits c)
      (let* ((state (sb-ext:seed-random-state 3))
             (q0 (random-q lo hi state))
             (target (chain-fk c q0)))
        ;; the same call gives the same answer, bit for bit
        (dotimes (k 5)
          (let ((seed (random-q lo hi state)))
            (is (equalp (chain-ik c target :seed seed :random-seed (+ 7 k))
                        (chain-ik c target :seed seed :random-seed (+ 7 k))))))
        ;; a seed that already solves the pose is the answer
        (let ((q (chain-ik c target :seed q0)))
          (is (every (lambda (a b) (approx a b 1d-12)) q q0)))
        ;; continuous joints (forearm and wrist roll) come back within [-pi, pi]
        (let ((q (chain-ik c target :seed (map '(simple-array double-float (*)) (lambda (x) (+ x (* 4 pi))) q0))))
          (is-true q)
          (when q
            (is (every (lambda (x a b) (<= (- a 1d-12) x (+ b 1d-12))) q lo hi))))
        ;; out of reach: no answer, and the reported error says how far the best attempt is
        (multiple-value-bind (q err) (chain-ik c '(2 0 0 0 0 0 1) :max-restarts 5)
          (is (null q))
          (is (> (aref err 0) 0.5d0)))))))

(defun check-chain-round-trips (w r base joints seed)
  "The chain BASE -> r_gripper_tool_frame of robot R has JOINTS joints and solves at least 99 of
100 random reachable poses (random state seeded with SEED)."
  (let ((c (make-chain w r base "r_gripper_tool_frame")))
    (unwind-protect
         (multiple-value-bind (solved problems)
             (ik-round-trips c 100 (sb-ext:seed-random-state seed))
           (is (= joints (chain-joint-count c)))
           (is (>= solved 99))
           (is (null problems) "~s" problems))
      (destroy-chain c))))

(test ik-prismatic-and-short-chains
  (if (not (probe-file *ik-pr2-urdf*))
      (skip "no PR2 model at ~a" *ik-pr2-urdf*)
      (progn
        (with-world (w)
          (let ((r (add-urdf w (uiop:read-file-string *ik-pr2-urdf*))))
            ;; base_link -> tool frame: the prismatic torso joint and the arm (8 joints)
            (check-chain-round-trips w r "base_link" 8 5)
            ;; elbow -> tool frame: 3 joints, still exact on poses it can reach
            (check-chain-round-trips w r "r_elbow_flex_link" 3 6))))))

(test ik-memo-keeps-only-answers-the-restarts-play-no-part-in
  ;; a chain asked again gives what a chain asked for the first time gives, bit for bit, for
  ;; goals solved from the seed, goals out of reach and goals only a restart solves (whose
  ;; answer depends on the random seed: not kept)
  (if (not (probe-file *ik-pr2-urdf*))
      (skip "no PR2 model at ~a" *ik-pr2-urdf*)
      (with-world (w)
        (let* ((r (add-urdf w (uiop:read-file-string *ik-pr2-urdf*)))
               (c (make-chain w r "torso_lift_link" "r_wrist_roll_link"))
               (fresh (make-chain w r "torso_lift_link" "r_wrist_roll_link"))
               (state (sb-ext:seed-random-state 21)) (restart-dependent 0))
          (unwind-protect
               (multiple-value-bind (lo hi) (chain-limits c)
                 (dotimes (k 40)
                   (let* ((q0 (random-q lo hi state))
                          (target (if (zerop (mod k 4)) '(2 0 0 0 0 0 1) (chain-fk c q0)))
                          ;; every other goal seeded where it is solved, the others far away
                          (seed (if (evenp k) q0 (random-q lo hi state))))
                     (chain-ik c target :seed seed :random-seed 1)
                     (multiple-value-bind (q err) (chain-ik c target :seed seed :random-seed 2)
                       (multiple-value-bind (q2 err2) (chain-ik fresh target :seed seed :random-seed 2)
                         (is (equalp (list q err) (list q2 err2)) "goal ~d: asked again ~s ~s, fresh ~s ~s"
                             k q err q2 err2))
                       (unless (equalp q (chain-ik fresh target :seed seed :random-seed 1))
                         (incf restart-dependent)))))
                 (is (plusp restart-dependent) "no goal's answer depended on the random seed")
                 (is (< 0 (chain-ik-memo-size c) 40))
                 ;; never more than 4096 answers, however many goals are asked
                 (loop for k below 5000
                       do (chain-ik c (list (+ 2 (* k 1d-3)) 0 0 0 0 0 1) :max-restarts 0))
                 (is (<= 1 (chain-ik-memo-size c) 4096)))
            (destroy-chain fresh)
            (destroy-chain c))))))
