;;;; Tests of ARM-IK's lookups: the arm's IK chain kept while the facts are the same, and the
;;;; parts ARM-IK and MOVE-TCP's search share (CHAIN-IK-FROM-MAP, FIRST-JOINT-CHILD).

(in-package :cram-plans-tests.urdf-proj)

(in-suite urdf-proj)

(defun chain-lookups (thunk)
  "Call THUNK; return how often the arm facts were consulted for an IK chain meanwhile."
  (values (calls-during 'urdf-proj::find-arm-ik-chain thunk)))

(test arm-ik-chains-are-kept-while-the-facts-are-the-same
  (with-kitchen
    (let ((left (urdf-proj:arm-ik-chain :left (robot))))
      (is (equal "torso_lift_link" (urdf-proj:ik-chain-base-link left)))
      (is (equal "l_wrist_roll_link" (urdf-proj:ik-chain-tip-link left)))
      (is (eq left (urdf-proj::find-arm-ik-chain :left (robot))))
      (is (= 0 (chain-lookups (lambda ()
                                (is (eq left (urdf-proj:arm-ik-chain :left (robot))))
                                (is (eq left (urdf-proj:arm-ik-chain :left (robot))))))))
      (is (equal "r_wrist_roll_link"
                 (urdf-proj:ik-chain-tip-link (urdf-proj:arm-ik-chain :right (robot)))))
      ;; a changed database: the facts are read again once
      (unwind-protect
           (progn
             (prolog:add-fact '(rob-int:arm-joints :no-such-robot :left ("j")))
             (is (= 1 (chain-lookups (lambda ()
                                       (is (eq left (urdf-proj:arm-ik-chain :left (robot))))
                                       (is (eq left (urdf-proj:arm-ik-chain :left (robot)))))))))
        (prolog:remove-facts '(rob-int:arm-joints :no-such-robot ?arm ?joints)))
      ;; arm joints from a rule that reads Lisp: the facts are read on every call
      (unwind-protect
           (progn
             (eval '(prolog:def-fact-group arm-chain-test-robot (rob-int:arm-joints)
                     (prolog:<- (rob-int:arm-joints :arm-chain-bot ?arm ?joints)
                       (prolog:lisp-fun list ?arm ?joints))))
             (is (= 2 (chain-lookups (lambda ()
                                       (urdf-proj:arm-ik-chain :left (robot))
                                       (urdf-proj:arm-ik-chain :left (robot)))))))
        (prolog:remove-fact-group 'arm-chain-test-robot))
      (signals error (urdf-proj:arm-ik-chain :third-arm (robot))))))

(test arm-ik-parts-agree-with-arm-ik
  (with-kitchen
    (let* ((chain (urdf-proj:arm-ik-chain :left (robot)))
           (ee (urdf-proj:end-effector-link :left))
           (child (urdf-proj::first-joint-child chain (robot)))
           ;; where the wrist is for a bent arm: a pose the arm reaches
           (q '(0.5 0.3 0.2 -1.0 0.4 -0.6 0.1))
           (reachable (cl-transforms:transform->pose
                       (cl-transforms:transform*
                        (cl-transforms:pose->transform (btr:link-pose (robot) "torso_lift_link"))
                        (cl-transforms:pose->transform (urdf-proj:chain-forward-kinematics chain q)))))
           (far (cl-transforms:make-pose (cl-transforms:make-3d-vector 3 3 3)
                                         (cl-transforms:make-identity-rotation))))
      (is (equal "l_shoulder_pan_link" child))
      (let ((a (let ((urdf-proj:*ik-random-state* (sb-ext:seed-random-state 7)))
                 (urdf-proj:arm-ik :left reachable :robot (robot))))
            (b (let ((urdf-proj:*ik-random-state* (sb-ext:seed-random-state 7)))
                 (urdf-proj::chain-ik-from-map chain ee child reachable (robot) nil
                                               urdf-proj::*ik-max-restarts*))))
        (is (= 7 (length a)))
        (is (equal a b)))
      (is (null (urdf-proj:arm-ik :left far :robot (robot))))
      (is (null (urdf-proj::chain-ik-from-map chain ee child far (robot) nil 3)))
      (signals error (urdf-proj::first-joint-child
                      (urdf-proj::%make-ik-chain :joint-names #("no_such_joint")) (robot))))))

(test reach-maps-kept-for-chains-made-again
  ;; KEEP-REACH-MAPS keeps the maps of the cached chains; the chains made after the cache is
  ;; cleared (as in the process a saved core starts) take them instead of building them
  (with-kitchen
    (let ((urdf-proj::*kept-reach-maps* '()))
      (urdf-proj:arm-ik-chain :left (robot))
      (urdf-proj:arm-ik-chain :right (robot))
      (is (<= 2 (urdf-proj::keep-reach-maps)))
      (let ((kept (length urdf-proj::*kept-reach-maps*)))
        (is (= kept (urdf-proj::keep-reach-maps)) "kept again: ~d maps" kept))
      (let ((installed 0))
        (sb-int:encapsulate 'urdf-proj::install-kept-reach-map 'count
                            (lambda (f native) (let ((r (funcall f native))) (when r (incf installed)) r)))
        (unwind-protect
             (progn
               (urdf-proj::clear-ik-chain-cache)
               (let ((left (urdf-proj:arm-ik-chain :left (robot))))
                 (is (= 1 installed))
                 (is (equalp (cram-native:chain-reach-map (urdf-proj::ik-chain-native left))
                             (find (car (cram-native:chain-reach-map (urdf-proj::ik-chain-native left)))
                                   urdf-proj::*kept-reach-maps* :key #'car :test #'equalp)))))
          (sb-int:unencapsulate 'urdf-proj::install-kept-reach-map 'count))))))
