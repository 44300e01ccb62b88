;;;; Tests of the reach map of a kinematic chain (CHAIN-MAY-REACH-P): it never rules out a
;;;; position the chain's tip can take, it rules out much of what lies beyond the arm, and the
;;;; IK gives such a goal up with the seed's error.

(in-package :cram-native-tests)

(in-suite native)

(test reach-map-never-rules-out-a-tip-position
  ;; 20 000 random configurations within the limits of each arm chain: every tip position is
  ;; "may reach", at the IK's tolerance and at none
  (dolist (tip '("l_wrist_roll_link" "r_wrist_roll_link" "r_gripper_tool_frame"))
    (with-pr2-chain (c tip)
      (multiple-value-bind (lo hi) (chain-limits c)
        (let ((state (sb-ext:seed-random-state 41)) (ruled-out '()))
          (dotimes (k 20000)
            (let ((p (subseq (chain-fk c (random-q lo hi state)) 0 3)))
              (unless (and (chain-may-reach-p c p) (chain-may-reach-p c p :position-tolerance 1d-9))
                (push p ruled-out))))
          (is (null ruled-out) "~a: ~d tip positions ruled out, e.g. ~s" tip (length ruled-out)
              (first ruled-out)))))))

(test reach-map-agrees-with-the-ik-and-rules-out-goals-beyond-the-arm
  ;; random goals in a 2.4 m cube around the torso: whatever the IK (40 restarts) solves is
  ;; "may reach"; of the goals it cannot solve, the map rules out most (those well beyond the
  ;; arm), and the IK's answer for a ruled-out goal is the seed's error
  (with-pr2-chain (c "r_wrist_roll_link")
    (multiple-value-bind (lo hi) (chain-limits c)
      (let ((state (sb-ext:seed-random-state 5)) (solved 0) (unsolved 0) (ruled-out 0)
            (wrong '()))
        (dotimes (k 400)
          (let* ((goal (concatenate 'list
                                    (loop repeat 3 collect (- (random 2.4d0 state) 1.2d0))
                                    (subseq (chain-fk c (random-q lo hi state)) 3 7)))
                 (may (chain-may-reach-p c (subseq goal 0 3)))
                 (q (chain-ik c goal :max-restarts 40 :random-seed (1+ k))))
            (cond (q (incf solved) (unless may (push goal wrong)))
                  (t (incf unsolved) (unless may (incf ruled-out))))))
        (is (null wrong) "solved goals ruled out: ~s" wrong)
        (is (< 10 solved) "only ~d of 400 goals solved" solved)
        (format t "~&  reach map: ~d of 400 random goals solved, ~d of the ~d unsolved ruled out~%" solved ruled-out unsolved)
        (is (> ruled-out (* 0.6 unsolved)) "only ~d of ~d unsolved goals ruled out" ruled-out unsolved))
      ;; out of reach by far: ruled out, the IK answers at once with the seed's error
      (let ((seed (map '(simple-array double-float (*)) (lambda (a b) (* 0.5d0 (+ a b))) lo hi)))
        (is (not (chain-may-reach-p c '(1.5 0 0.2))))
        (multiple-value-bind (q err) (chain-ik c '(1.5 0 0.2 0 0 0 1) :seed seed :max-restarts 40)
          (is (null q))
          (multiple-value-bind (pe) (pose-errors (chain-fk c seed) (coerce '(1.5d0 0d0 0.2d0 0d0 0d0 0d0 1d0) '(simple-array double-float (*))))
            (is (approx pe (aref err 0) 1d-6) "error ~s, the seed's ~s" (aref err 0) pe)))))))

(test reach-map-bad-input
  (with-pr2-chain (c "r_wrist_roll_link")
    (signals-naming ("position" "NaN") (chain-may-reach-p c (list 0 (nan) 0)))
    (signals-naming ("position" "3 reals") (chain-may-reach-p c '(0 0)))
    (signals-naming ("position tolerance") (chain-may-reach-p c '(0 0 0) :position-tolerance -1))
    ;; a tolerance the map does not answer for: always "may"
    (is-true (chain-may-reach-p c '(5 0 0) :position-tolerance 0.5))))

(test reach-map-kept-and-given-back
  ;; a chain made again (as in the process a saved core starts) takes the kept map instead of
  ;; building it: the same answers everywhere; a map of another chain is refused and changes
  ;; nothing; what is no map is an error
  (with-pr2-chain (c "r_wrist_roll_link")
    (let ((map (chain-reach-map c)))
      (is (= 20 (length (car map))))
      (is (< 10000 (length (cdr map))) "only ~d cells" (length (cdr map)))
      (with-pr2-chain (again "r_wrist_roll_link")
        (is-true (set-chain-reach-map again map))
        (is (equalp map (chain-reach-map again)))
        (let ((state (sb-ext:seed-random-state 9)) (differ '()))
          (dotimes (k 5000)
            (let ((p (loop repeat 3 collect (- (random 2.4d0 state) 1.2d0))))
              (unless (eq (chain-may-reach-p c p) (chain-may-reach-p again p))
                (push p differ))))
          (is (null differ) "answers differ at ~s" (first differ))))
      (with-pr2-chain (left "l_wrist_roll_link")
        (let ((own (chain-reach-map left)))
          (is-false (set-chain-reach-map left map))
          (is (equalp own (chain-reach-map left)))))
      (signals error (set-chain-reach-map c (cons (car map) "cells")))
      (signals error (set-chain-reach-map c (cons (subseq (car map) 0 5) (cdr map)))))))
