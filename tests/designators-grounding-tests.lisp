;;;; Tests of designator grounding: Prolog groundings, location generators and validators.

(in-package :cram-designators-tests)

(in-suite designators)

;;; Action and motion groundings through Prolog

(prolog:def-fact-group designators-test-groundings (desig:action-grounding
                                                    desig:motion-grounding)
  (prolog:<- (desig:action-grounding ?d (test-plan-a ?d))
    (desig:desig-prop ?d (:type :desig-test-action)))
  (prolog:<- (desig:action-grounding ?d (test-plan-b ?d))
    (desig:desig-prop ?d (:type :desig-test-action)))
  (prolog:<- (desig:motion-grounding ?d (test-move ?x))
    (desig:desig-prop ?d (:type :desig-test-motion))
    (desig:desig-prop ?d (:target ?x))))

(test action-reference-and-next-solution
  (let* ((d (desig:an action (type desig-test-action) (arm left)))
         (grounding (desig:reference d)))
    (is (eq 'test-plan-a (first grounding)))
    (is (eq d (second grounding)))
    (is (eq grounding (desig:reference d)))
    (is (desig:effective d))
    (let ((next (desig:next-solution d)))
      (is (not (null next)))
      (is (desig:desig-equal d next))
      (is (eq 'test-plan-b (first (desig:reference next))))
      (is (null (desig:next-solution next))))))

(test motion-reference
  (let* ((?target 5)
         (d (desig:a motion (type desig-test-motion) (target ?target))))
    (is (equal '(test-move 5) (desig:reference d)))))

(test reference-without-grounding-names-designator
  (let* ((d (desig:an action (type desig-test-unknown-action)))
         (text (handler-case (progn (desig:reference d) "")
                 (desig:designator-error (e)
                   (is (eq d (desig:designator-error-designator e)))
                   (princ-to-string e)))))
    (is (search "DESIG-TEST-UNKNOWN-ACTION" text))
    (is (search "ACTION-GROUNDING" text))))

(test reset-drops-solutions
  (let* ((d (desig:an action (type desig-test-action)))
         (next (progn (desig:reference d) (desig:next-solution d)))
         (fresh (desig:reset d)))
    (is (desig:desig-equal d fresh))
    (is (eq fresh (desig:current-desig next)))
    (is (not (desig:effective fresh)))
    (is (eq 'test-plan-a (first (desig:reference fresh))))))

(test prolog-designator-construction
  (let* ((bindings (first (prolog:prolog '(and (desig:designator :action ((:type :going) (:arm ?a))
                                                                 ?d)
                                               (desig:desig-prop ?d (:type ?type)))
                                         '((?a . :left)))))
         (d (cut:var-value '?d bindings))
         (type (cut:var-value '?type bindings)))
    (is (typep d 'desig:action-designator))
    (is (equal '((:type :going) (:arm :left)) (desig:description d)))
    (is (eq :going type))))

(test prolog-inspection-predicates
  (let* ((d (desig:a location (pose 7) (side left)))
         (type (cut:var-value '?type (first (prolog:prolog `(desig:desig-class ,d ?type)))))
         (side (cut:var-value '?v (first (prolog:prolog `(desig:desig-prop ,d (:side ?v))))))
         (keys (mapcar (lambda (b) (cut:var-value '?k b))
                       (cut:force-ll (prolog:prolog `(desig:desig-prop ,d (?k ?_)))))))
    (is (eq :location type))
    (is (eq :left side))
    (is (equal '(:pose :side) keys))
    (is (not (null (prolog:prolog `(desig:loc-desig? ,d)))))
    (is (null (prolog:prolog `(desig:action-desig? ,d))))))

;; desig-prop gives the entries of a key in the order of the description, unifies the value
;; with what is asked, and matches no entry of another form
(test desig-prop-entries-in-order
  (let ((d (desig:an action (type picking-up) (arm left) (grasp front) (arm right))))
    (flet ((values-of (goal var)
             (mapcar (lambda (b) (cut:var-value var b)) (cut:force-ll (prolog:prolog goal)))))
      (is (equal '(:left :right) (values-of `(desig:desig-prop ,d (:arm ?v)) '?v)))
      (is (equal '((:type :picking-up) (:arm :left) (:grasp :front) (:arm :right))
                 (values-of `(desig:desig-prop ,d ?p) '?p)))
      (is (equal '(:arm) (values-of `(desig:desig-prop ,d (?k :right)) '?k)))
      (is (equal '(:type :arm :grasp :arm) (values-of `(desig:desig-prop ,d (?k ?_)) '?k)))
      (is (equal '(:left) (values-of `(and (desig:desig-prop ,d (:arm ?v)) (cut)) '?v)))
      (is (null (prolog:prolog `(desig:desig-prop ,d (:arm :front)))))
      (is (null (prolog:prolog `(desig:desig-prop ,d (:color ?c)))))
      (is (null (prolog:prolog `(desig:desig-prop ,d (:arm)))))
      (is (null (prolog:prolog '(desig:desig-prop not-a-designator (:arm ?v)))))
      (is (null (prolog:prolog '(desig:desig-prop ?unbound (:arm ?v))))))))

;;; Location designators

(defvar *generated-candidates* 0)

(defun test-sampler-generator (designator)
  "Candidates (i 0 0) for i below the designator's :TEST-SAMPLES; endless odd candidates for
designators with :TEST-ENDLESS."
  (let ((samples (desig:desig-prop-value designator :test-samples)))
    (cond (samples
           (cut:lazy-list ((i 0))
             (if (< i samples)
                 (cut:cont (list i 0 0) (1+ i))
                 (cut:finish))))
          ((desig:desig-prop-value designator :test-endless)
           (cut:lazy-list ((i 0))
             (incf *generated-candidates*)
             (cut:cont (list 1 i 0) (1+ i))))
          (t nil))))

(defun test-odd-validator (designator candidate)
  "Reject odd x for the test designators; no opinion otherwise."
  (if (and (or (desig:desig-prop-value designator :test-samples)
               (desig:desig-prop-value designator :test-endless))
           (oddp (first candidate)))
      :reject
      :unknown))

(defun test-maybe-validator (designator candidate)
  "Maybe-reject x = 2 for designators with :TEST-MAYBE."
  (if (and (desig:desig-prop-value designator :test-maybe) (eql 2 (first candidate)))
      :maybe-reject
      :unknown))

(defun test-accept-four-validator (designator candidate)
  "Accept x = 4 for designators with :TEST-MAYBE."
  (if (and (desig:desig-prop-value designator :test-maybe) (eql 4 (first candidate)))
      :accept
      :unknown))

(defmacro with-test-location-functions (&body body)
  `(unwind-protect
        (progn
          (desig:register-location-generator 1 test-sampler-generator "test candidates")
          (desig:register-location-validation-function 1 test-odd-validator "no odd x")
          ,@body)
     (desig:delete-location-generator-function 'test-sampler-generator)
     (desig:delete-location-validation-function 'test-odd-validator)))

(test location-generator-and-next-solution
  (with-test-location-functions
    (is (member 'test-sampler-generator (mapcar #'first (desig:location-generators))))
    (let* ((d (desig:a location (test-samples 6)))
           (first-solution (desig:reference d))
           (second-designator (desig:next-solution d))
           (third-designator (desig:next-solution second-designator)))
      (is (equal '(0 0 0) first-solution))
      (is (equal '(2 0 0) (desig:reference second-designator)))
      (is (equal '(4 0 0) (desig:reference third-designator)))
      (is (null (desig:next-solution third-designator)))
      (is (desig:desig-equal d third-designator))
      (is (equal '((0 0 0) (2 0 0) (4 0 0))
                 (cut:force-ll (desig:designator-solutions d)))))))

(test location-validators-maybe-reject
  (unwind-protect
       (with-test-location-functions
         (desig:register-location-validation-function 2 test-maybe-validator)
         (desig:register-location-validation-function 3 test-accept-four-validator)
         (let ((d (desig:a location (test-samples 6) (test-maybe t))))
           (is (equal '((0 0 0) (4 0 0)) (cut:force-ll (desig:designator-solutions d))))))
    (desig:delete-location-validation-function 'test-maybe-validator)
    (desig:delete-location-validation-function 'test-accept-four-validator)))

(test location-retry-cap
  (with-test-location-functions
    (let ((*generated-candidates* 0)
          (desig:*location-generator-max-retries* 5)
          (d (desig:a location (test-endless t))))
      (signals desig:location-resolution-error (desig:reference d))
      (is (= 6 *generated-candidates*)))
    (let ((*generated-candidates* 0)
          (d (desig:a location (test-endless t))))
      (signals desig:designator-error (desig:reference d))
      (is (= (1+ desig:*location-generator-max-retries*) *generated-candidates*)))))

(defun test-bad-validator (designator candidate)
  "Answer with a verdict that is not allowed for designators with :TEST-BAD."
  (declare (ignore candidate))
  (if (desig:desig-prop-value designator :test-bad) :perhaps :unknown))

(test location-validator-bad-verdict
  (unwind-protect
       (progn
         (desig:register-location-validation-function 1 test-bad-validator)
         (let* ((?p '(1 2 3))
                (text (handler-case
                          (progn (desig:reference (desig:a location (pose ?p) (test-bad t))) "")
                        (error (e) (princ-to-string e)))))
           (is (search "PERHAPS" text))
           (is (search "TEST-BAD-VALIDATOR" text))))
    (desig:delete-location-validation-function 'test-bad-validator)))

(test location-pose-grounding
  (let* ((?pose '((1 2 3) (0 0 0 1)))
         (pose ?pose)
         (d (desig:a location (pose ?pose))))
    (is (equal pose (desig:reference d)))
    (is (null (desig:next-solution d))))
  (let* ((?poses '((0 0 0) (0.01 0 0) (1 0 0)))
         (d (desig:a location (poses ?poses))))
    (is (equal '(0 0 0) (desig:reference d)))
    (is (equal '(0.01 0 0) (desig:reference (desig:next-solution d))))
    (let ((far (desig:next-different-location-solution d 0.05)))
      (is (equal '(1 0 0) (desig:reference far)))
      (is (desig:desig-equal d far)))))

(test location-transforms-poses-distance
  (let* ((?poses (list (cl-transforms:make-pose (cl-transforms:make-3d-vector 0 0 0)
                                                (cl-transforms:make-identity-rotation))
                       (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.02 0 0)
                                                (cl-transforms:make-identity-rotation))
                       (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.02 0 0)
                                                (cl-transforms:axis-angle->quaternion
                                                 (cl-transforms:make-3d-vector 0 0 1) 1.0))))
         (d (desig:a location (poses ?poses)))
         (far (desig:next-different-location-solution d 0.05 0.5))
         (expected (third ?poses)))
    (is (eq expected (desig:reference far)))))

(test location-reference-failure-is-designator-error
  (let ((d (desig:a location (nowhere t))))
    (signals desig:location-resolution-error (desig:reference d))
    (is (typep (handler-case (desig:reference d) (error (e) e)) 'desig:designator-error))))
