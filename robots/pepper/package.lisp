;;;; Package CRAM-PEPPER-DESCRIPTION (nickname PEPPER-DESCR): the Pepper robot as Prolog
;;;; facts keyed by the robot name PEPPER.

(in-package :cl-user)

(defpackage cram-pepper-description
  (:nicknames #:pepper-descr)
  (:use #:common-lisp #:cram-prolog #:cram-robot-interfaces)
  (:export #:pepper))
