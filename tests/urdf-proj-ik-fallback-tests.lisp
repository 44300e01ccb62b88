;;;; Tests of the IK solvers' division of work: after the native solver of a chain failed (it
;;;; made its own random restarts), the Lisp solver tries only as URDF-PROJ::*IK-FALLBACK-RESTARTS*
;;;; says (by default not at all).

(in-package :cram-plans-tests.urdf-proj)

(in-suite urdf-proj)

(defun lisp-attempts (thunk)
  "Call THUNK; return how many attempts the Lisp IK solver made meanwhile, and THUNK's value."
  (calls-during 'urdf-proj::ik-attempt thunk))

(test ik-fallback-restarts-after-a-native-failure
  (with-kitchen
    (let* ((chain (urdf-proj:arm-ik-chain :left (robot)))
           ;; 2 m straight ahead of the torso: beyond the arm's reach
           (far (cl-transforms:make-pose (cl-transforms:make-3d-vector 2.0 0.2 0.0)
                                         (cl-transforms:make-identity-rotation)))
           (near (urdf-proj:chain-forward-kinematics chain '(0.5 0.3 0.2 -1.0 0.4 -0.6 0.1))))
      (is (urdf-proj::ik-chain-native chain) "the PR2's arm has a native chain")
      (multiple-value-bind (attempts solution)
          (lisp-attempts (lambda () (urdf-proj:solve-ik chain far :max-restarts 5)))
        (is (null solution))
        (is (= 0 attempts) "by default the Lisp solver does not try after a native failure"))
      (let ((urdf-proj::*ik-fallback-restarts* 0))
        (multiple-value-bind (attempts solution)
            (lisp-attempts (lambda () (urdf-proj:solve-ik chain far :max-restarts 5)))
          (is (null solution))
          (is (= 1 attempts) "only the Lisp solver's seeded attempt")))
      (let ((urdf-proj::*ik-fallback-restarts* 2))
        (multiple-value-bind (attempts solution)
            (lisp-attempts (lambda () (urdf-proj:solve-ik chain far :max-restarts 5)))
          (is (null solution))
          (is (= 3 attempts) "the seeded attempt and two random ones")))
      (let ((urdf-proj::*ik-fallback-restarts* 9))
        (is (= 6 (lisp-attempts (lambda () (urdf-proj:solve-ik chain far :max-restarts 5))))
            "never more than MAX-RESTARTS"))
      ;; without the native solver, the Lisp solver makes all its restarts
      (is (= 6 (lisp-attempts (lambda () (urdf-proj:solve-ik chain far :max-restarts 5
                                                                         :use-native nil)))))
      ;; a reachable goal: the native solver answers, the Lisp solver does not run
      (multiple-value-bind (attempts solution) (lisp-attempts (lambda () (urdf-proj:solve-ik chain near)))
        (is (= 0 attempts))
        (is (= 7 (length solution)))))))
