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

(test search-lookups-read-the-joints-as-they-are
  (with-kitchen
    (let* ((robot (robot))
           (chain (urdf-proj:arm-ik-chain :left robot))
           (joints (cram-native:robot-joints (btr::whandle robot) (btr:object-handle robot))))
      ;; the seed from the joint vector is each chain joint's own value
      (is (equal (map 'list (lambda (j) (btr:joint-state robot j)) (urdf-proj:ik-chain-joint-names chain))
                 (urdf-proj::chain-joint-values chain robot joints)))
      ;; the torso values: the same list again for the same torso, new ones once it moved
      (let* ((torso (urdf-proj:torso-joint))
             (before (btr:joint-state robot torso))
             (first (urdf-proj::torso-candidates robot nil)))
        (is (= before (first first)))
        (is (eq first (urdf-proj::torso-candidates robot nil)))
        (is (equal (list before) (urdf-proj::torso-candidates robot t)))
        (unwind-protect
             (let ((moved (+ before (if (> before 0.1d0) -0.05d0 0.05d0))))
               (btr:set-robot-state-from-joints (list (list torso moved)) robot)
               (let ((second (urdf-proj::torso-candidates robot nil)))
                 (is (= moved (first second)))
                 (is (not (eq first second)))
                 (is (equal (sort (copy-list second) #'<)
                            (sort (copy-list (urdf-proj::torso-values moved
                                                                      (btr:joint-lower-limit robot torso)
                                                                      (btr:joint-upper-limit robot torso)))
                                  #'<)))))
          (btr:set-robot-state-from-joints (list (list torso before)) robot))))
    ;; a robot state put back from its vectors: base and every joint as they were
    (let* ((robot (robot))
           (state (urdf-proj::robot-state-vectors robot))
           (pose (btr:pose robot))
           (joints (btr:joint-states robot)))
      (setf (btr:pose robot) (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.3 0.2 0)
                                                      (cl-transforms:make-identity-rotation)))
      (btr:set-robot-state-from-joints '(("l_elbow_flex_joint" -1.0d0) ("torso_lift_joint" 0.2d0)) robot)
      (urdf-proj::restore-robot-state robot state)
      (is (< (btr::pose-distance pose (btr:pose robot)) 1d-12))
      (is (equal joints (btr:joint-states robot)))
      (is (eq (urdf-proj::all-joint-indices 5) (urdf-proj::all-joint-indices 5)))
      (is (equalp #(0 1 2 3 4) (urdf-proj::all-joint-indices 5))))))

(test base-offset-shifts-are-kept-for-the-same-heading
  (let* ((candidates (urdf-proj::base-candidates t))
         (a (cl-transforms:make-pose (cl-transforms:make-3d-vector 1 2 0)
                                     (cl-transforms:axis-angle->quaternion
                                      (cl-transforms:make-3d-vector 0 0 1) 0.7d0)))
         (b (cl-transforms:make-pose (cl-transforms:make-3d-vector -1 0 0)
                                     (cl-transforms:orientation a)))
         (c (cl-transforms:make-pose (cl-transforms:make-3d-vector 1 2 0)
                                     (cl-transforms:axis-angle->quaternion
                                      (cl-transforms:make-3d-vector 0 0 1) -0.2d0)))
         (shifts (urdf-proj::base-offset-shifts a candidates)))
    (is (= (length candidates) (length shifts)))
    (is (every (lambda (o s) (equalp s (urdf-proj::base-offset-shift a (first o) (second o))))
               candidates shifts))
    ;; another position with the same heading: the same shifts, not made again
    (is (eq shifts (urdf-proj::base-offset-shifts b candidates)))
    ;; another heading: made again, and right for it
    (let ((turned (urdf-proj::base-offset-shifts c candidates)))
      (is (not (eq shifts turned)))
      (is (every (lambda (o s) (equalp s (urdf-proj::base-offset-shift c (first o) (second o))))
                 candidates turned)))))
