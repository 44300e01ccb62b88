;;;; Tests of ROB-INT's CRAM variables and functions: the description parameter, the environment
;;;; URDF and name, visibility and reachability designators; DESIG:DATA.

(defpackage :cram-robot-interfaces-api-tests
  (:use :cl :fiveam))

(in-package :cram-robot-interfaces-api-tests)

(def-suite robot-interfaces-api :in cram-plans-tests:all
  :description "ROB-INT variables, GET-ENVIRONMENT-NAME, VISIBILITY-DESIGNATOR, DESIG:DATA.")
(in-suite robot-interfaces-api)

(defun kitchen-urdf ()
  (cl-urdf:parse-urdf (asdf:system-relative-pathname "cram-plans/cram-bullet-reasoning"
                                                     "resources/iai_kitchen.urdf")))

(test robot-description-parameter-default
  (is (equal "robot_description" rob-int:*robot-description-parameter*)))

(test environment-name-from-the-world-or-the-urdf
  (let ((btr:*current-bullet-world* (make-instance 'btr:bt-reasoning-world))
        (btr:*environment-name* nil)
        (rob-int:*environment-urdf* nil))
    (signals rob-int:robot-interface-error (rob-int:get-environment-name))
    (setf rob-int:*environment-urdf* (kitchen-urdf))
    (is (eq :iai-kitchen (rob-int:get-environment-name)))
    (btr:add-object btr:*current-bullet-world* :urdf :my-kitchen '((0 0 0) (0 0 0 1))
                    :urdf rob-int:*environment-urdf* :collision-group :static-filter)
    (is (eq :my-kitchen (rob-int:get-environment-name)) "the environment object of the world")))

(test get-robot-name-is-the-current-robot
  (let ((rob-int:*robot-name* :pr2))
    (is (eq :pr2 (rob-int:get-robot-name)))))

(test visibility-and-reachability-designators
  (let ((see (desig:a location (visible-for pr2) (object (desig:an object (type bottle)))))
        (reach (desig:a location (reachable-for pr2) (object (desig:an object (type bottle)))))
        (on (desig:a location (on (desig:an object (type counter-top))))))
    (is-true (rob-int:visibility-designator-p see))
    (is-false (rob-int:visibility-designator-p reach))
    (is-true (rob-int:reachability-designator-p reach))
    (is-false (rob-int:reachability-designator-p on))
    (is-false (rob-int:visibility-designator-p (desig:an object (visible-for pr2))))
    (is-false (rob-int:visibility-designator-p 42))
    (is (= 1 (length (cut:force-ll (prolog:prolog `(rob-int:visibility-designator ,see))))))))

(test desig-data-is-the-cached-reference
  (let ((d (desig:a location (pose ((1 2 0) (0 0 0 1))))))
    (is (null (desig:data d)))
    (let ((reference (desig:reference d)))
      (is (eq reference (desig:data d))))
    (signals error (desig:data 42))))

(defvar *test-frame* nil "The frame the rule of FACT-ANSWERS-ARE-KEPT-WHILE-THE-FACTS-ARE-THE-SAME answers.")
(defun test-frame () *test-frame*)

(test fact-answers-are-kept-while-the-facts-are-the-same
  "Queries over plain facts are answered from the kept solutions until the database changes;
queries over rules (Lisp, special variables) run every time."
  (unwind-protect
       (progn
         (eval '(prolog:def-fact-group fact-answers-test-robot (rob-int:arm rob-int:robot-odom-frame)
                 (prolog:<- (rob-int:arm :fact-answers-bot :left))
                 (prolog:<- (rob-int:arm :fact-answers-bot :right))
                 (prolog:<- (rob-int:robot-odom-frame :fact-answers-bot "odom_a"))))
         (let ((query '(rob-int:arm :fact-answers-bot ?arm)))
           (is (rob-int::plain-facts-p 'rob-int:arm))
           (is (equal '(:left :right) (rob-int::robot-arms :fact-answers-bot)))
           (is (eq (rob-int::fact-solutions query) (rob-int::fact-solutions query))
               "the same kept solutions")
           (is (= 2 (length (rob-int::cached-fact-solutions query))))
           (is (equal "odom_a" (rob-int::first-solution-value
                                '?f '(rob-int:robot-odom-frame :fact-answers-bot ?f))))
           ;; the facts change: the next answers are the new ones
           (eval '(prolog:def-fact-group fact-answers-test-robot (rob-int:arm rob-int:robot-odom-frame)
                   (prolog:<- (rob-int:arm :fact-answers-bot :left))
                   (prolog:<- (rob-int:robot-odom-frame :fact-answers-bot "odom_b"))))
           (is (equal '(:left) (rob-int::robot-arms :fact-answers-bot)))
           (is (equal "odom_b" (rob-int::first-solution-value
                                '?f '(rob-int:robot-odom-frame :fact-answers-bot ?f))))
           (multiple-value-bind (value found)
               (rob-int::first-solution-value '?f '(rob-int:robot-odom-frame :no-such-bot ?f))
             (is (null value))
             (is (null found)))))
    (prolog:remove-fact-group 'fact-answers-test-robot))
  ;; a predicate of rules: never kept, its answers follow the Lisp state
  (unwind-protect
       (progn
         (eval '(prolog:def-fact-group fact-answers-rule-robot (rob-int:robot-base-frame)
                 (prolog:<- (rob-int:robot-base-frame :fact-answers-bot ?frame)
                   (prolog:lisp-fun cram-robot-interfaces-api-tests::test-frame ?frame))))
         (is (not (rob-int::plain-facts-p 'rob-int:robot-base-frame)))
         (let ((query '(rob-int:robot-base-frame :fact-answers-bot ?f)))
           (is (null (nth-value 1 (rob-int::cached-fact-solutions query))))
           (setf *test-frame* "base_a")
           (is (equal "base_a" (rob-int::first-solution-value '?f query)))
           (setf *test-frame* "base_b")
           (is (equal "base_b" (rob-int::first-solution-value '?f query)))))
    (prolog:remove-fact-group 'fact-answers-rule-robot)))
