;;;; Tests of REGISTER-DESIGNATOR-CLASS as CRAM's macro and of designator classes of one's own,
;;;; described by something other than a list of properties.

(defpackage :cram-designator-classes-tests
  (:use :cl :fiveam))

(in-package :cram-designator-classes-tests)

(def-suite designator-classes :in cram-plans-tests:all
  :description "REGISTER-DESIGNATOR-CLASS and designators of one's own classes.")
(in-suite designator-classes)

(defclass frame-designator (desig:designator) ()
  (:documentation "A designator described by the name of a TF frame."))

(defmethod desig:reference ((designator frame-designator) &optional role)
  (declare (ignore role))
  (setf (desig:designator-data designator)
        (format nil "/~a" (desig:description designator))))

(desig:register-designator-class frame frame-designator)

(test register-designator-class-takes-unevaluated-names
  (is (eq 'frame-designator (desig:find-designator-class :frame)))
  (is (eq :frame (desig:register-designator-class 'frame 'frame-designator)) "quoted as well")
  (is (eq :frame (desig:designator-type (desig:make-designator :frame "base_link"))))
  (signals error (eval '(desig:register-designator-class 42 frame-designator)))
  (signals error (desig::%register-designator-class "frame" 'frame-designator)))

(test designators-of-ones-own-class-keep-their-description
  (let ((d (desig:make-designator 'frame "base_link")))
    (is (typep d 'frame-designator))
    (is (equal "base_link" (desig:description d)))
    (is (equal "/base_link" (desig:reference d)))
    (is (equal "/base_link" (desig:data d)))
    (is (null (desig:desig-prop-value d :anything)) "no properties, and no error")
    (is (search "base_link" (princ-to-string d))))
  (let ((d (desig:make-designator :frame '((:name "x")))))
    (is (equal '((:name "x")) (desig:description d)) "a list is normalised as usual")
    (is (equal "x" (desig:desig-prop-value d :name)))))

(test built-in-designators-still-need-property-lists
  (signals error (desig:make-designator :action "go"))
  (signals error (desig:make-designator :location 42))
  (signals error (desig:make-designator :object '(type bottle))))
